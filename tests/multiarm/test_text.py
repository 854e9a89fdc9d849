from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from multiarm.text import fmt_float, quote, unquote


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_fmt_float_round_trips(x: float) -> None:
    y = float(fmt_float(x))
    assert y == x and math.copysign(1, y) == math.copysign(1, x)


def test_fmt_float_rejects_non_finite() -> None:
    with pytest.raises(ValueError):
        fmt_float(math.inf)


@given(st.text())
def test_quote_round_trips(s: str) -> None:
    assert unquote(quote(s)) == s
