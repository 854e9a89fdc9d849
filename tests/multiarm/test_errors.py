from __future__ import annotations

import pickle

import pytest

from multiarm import errors as e


def test_families() -> None:
    assert issubclass(e.ValidationError, e.InputError)
    assert issubclass(e.InputError, ValueError)
    assert issubclass(e.InternalError, RuntimeError)
    assert issubclass(e.NoFeasibleSchedule, e.InfeasibleError)
    assert issubclass(e.PlanningFailed, e.InfeasibleError)
    assert not issubclass(e.InfeasibleError, e.InputError)
    assert issubclass(e.TDLSyntaxError, e.TDLError)
    assert issubclass(e.TDLSyntaxError, e.ParseError)
    assert issubclass(e.SDLSyntaxError, e.SDLError)
    assert issubclass(e.SDLSyntaxError, e.ParseError)
    assert not issubclass(e.SDLError, e.TDLError)


def test_source_error_renders_location() -> None:
    err = e.SDLError("zone 'a' is empty", filename="c.sdl", line=4, column=2)
    assert str(err) == "c.sdl:4:2: zone 'a' is empty"
    assert (err.filename, err.line, err.column) == ("c.sdl", 4, 2)
    assert str(e.TDLError("x")) == "<string>: x"
    assert str(e.TDLError("x", line=3)) == "<string>:3: x"


def test_parse_error_lists_expected() -> None:
    err = e.TDLSyntaxError(
        "unexpected '}'", filename="a.tdl", line=1, column=5, expected=["'{'", "a name"]
    )
    assert str(err) == "a.tdl:1:5: unexpected '}' (expected '{', a name)"
    many = e.ParseError("bad", expected=[f"t{i}" for i in range(20)])
    assert str(many).endswith("t10, t11, ...)")


@pytest.mark.parametrize(
    "err",
    [
        e.SDLSyntaxError("bad", filename="f.sdl", line=2, column=3, expected=("NAME",)),
        e.TDLError("bad", filename="f.tdl", line=1),
        e.CycleError("cycle a -> b -> a", ("a", "b", "a")),
        e.ValidationError("plain"),
    ],
)
def test_errors_pickle(err: Exception) -> None:
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is type(err)
    assert str(back) == str(err)
    for attr in ("filename", "line", "column", "expected", "cycle"):
        assert getattr(back, attr, None) == getattr(err, attr, None)
