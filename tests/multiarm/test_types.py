from __future__ import annotations

import numpy as np
import pytest

from multiarm.types import as_rng, check_finite


def test_as_rng_is_deterministic_and_passes_generators_through() -> None:
    assert as_rng(5).random() == as_rng(5).random()
    g = np.random.default_rng(1)
    assert as_rng(g) is g
    with pytest.raises(TypeError, match="seed"):
        as_rng("7")  # type: ignore[arg-type]


def test_check_finite() -> None:
    assert check_finite([0.0, 1, -2.5])
    assert not check_finite([0.0, float("nan")])
    assert not check_finite([float("inf")])
