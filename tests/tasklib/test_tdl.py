"""TDL (S2.10): parsing, errors with locations, frames, printing round trips."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from multiarm.errors import TDLError, TDLSyntaxError, ValidationError
from tasklib.tdl import (
    Frame,
    Segment,
    TDLDocument,
    Trajectory,
    Waypoint,
    load_tdl,
    parse_tdl,
    print_tdl,
)
from tests.strategies import tdl_documents, tdl_token_soup

EXAMPLE = """
# a comment
frame fixture = (1.0, 0.5, 0.1) rpy(0, 0, 1.5707963267948966)
frame tool in fixture = (0, 0, 0.2)

trajectory pick {
    frame fixture
    speed 0.5
    taught { via (0, 0, 0.3)  stop (0.1, 0, 0) quat(1, 0, 0, 0) speed 0.2 }
    learned "rec-7" interp axis speed 0.8 {
        via (0.2, 0, 0)
        via (0.3, 0, 0)
    }
}
"""


def test_parse_example() -> None:
    doc = parse_tdl(EXAMPLE, "ex.tdl")
    assert doc.names() == ("pick",)
    assert [f.name for f in doc.frames] == ["fixture", "tool"]
    t = doc.trajectory("pick")
    assert t.frame == "fixture" and t.speed == 0.5
    assert [s.source for s in t.segments] == ["taught", "learned"]
    assert t.segments[1].label == "rec-7"
    assert t.segments[1].interpolation == "axis"
    assert [p.stop for _, p in t.waypoints()] == [False, True, False, False]
    assert t.segments[0].points[1].speed == 0.2
    assert t.segments[0].points[0].line == 9


def test_resolve_applies_frames_and_speed_inheritance() -> None:
    doc = parse_tdl(EXAMPLE)
    r = doc.resolve("pick")
    # fixture is turned by +90 deg about z: its x axis is the cell's y axis.
    np.testing.assert_allclose(r.positions[1], [1.0, 0.6, 0.1], atol=1e-12)
    np.testing.assert_allclose(r.positions[0], [1.0, 0.5, 0.4], atol=1e-12)
    assert r.speed.tolist() == [0.5, 0.2, 0.8, 0.8]
    assert r.linear.tolist() == [True, True, False, False]
    assert r.stop.tolist() == [False, True, False, False]
    # orientation: frame's for points without one; explicit identity in the
    # frame is the frame's rotation in the cell.
    np.testing.assert_allclose(
        np.abs(r.orientations[0]), [np.sqrt(0.5), 0, 0, np.sqrt(0.5)], atol=1e-12
    )
    assert np.allclose(np.linalg.norm(r.orientations, axis=1), 1.0)
    chained = doc.frame_matrix("tool")
    np.testing.assert_allclose(chained[:3, 3], [1.0, 0.5, 0.3], atol=1e-12)


@pytest.mark.parametrize(
    ("text", "line", "column", "expected"),
    [
        ("trajectory t { taught { stop (0, 0) } }", 1, 35, "','"),
        ("trajectory t {", 1, 15, "'}'"),
        ("frame", 1, 6, "a name"),
        ("trajectory t { taught interp zigzag { } }", 1, 30, "'linear'"),
        ("trajectory t {\n  taught {\n    stop (0, 0, 1) quat(1, 0, 0)\n  }\n}", 3, 32, "','"),
        ("trajectory t { taught { stop (0, 0, 1) } } @", 1, 44, "'trajectory'"),
    ],
)
def test_syntax_errors_are_located(text: str, line: int, column: int, expected: str) -> None:
    with pytest.raises(TDLSyntaxError) as info:
        parse_tdl(text, "bad.tdl")
    err = info.value
    assert (err.filename, err.line, err.column) == ("bad.tdl", line, column)
    assert expected in err.expected
    assert str(err).startswith(f"bad.tdl:{line}:{column}: ")


@pytest.mark.parametrize(
    ("text", "message", "line"),
    [
        ("trajectory t { taught { stop (0, 0, 1) speed 1.5 } }", "speed must be a fraction", 1),
        ("trajectory t { frame nowhere taught { stop (0, 0, 1) } }", "unknown frame 'nowhere'", 1),
        ("frame a in b = (0, 0, 0)", "unknown frame 'b'", 1),
        ("frame a in b = (0,0,0)\nframe b in a = (0,0,0)", "cycle", 1),
        ("frame a = (0,0,0)\nframe a = (1,0,0)", "defined twice", 2),
        (
            "trajectory t { taught { stop (0,0,0) } }\ntrajectory t { taught { stop (0,0,0) } }",
            "defined twice",
            2,
        ),
        ("trajectory t { taught { stop (0, 0, 1e999) } }", "non-finite", 1),
        ("trajectory t { taught { stop (0, 0, 1) quat(1, 1, 0, 0) } }", "unit quaternion", 1),
        ("trajectory t { }", "has no segment", 1),
        ("trajectory t { taught { } }", "at least one point", 1),
        ("frame cell = (0, 0, 0)", "reserved", 1),
        ("trajectory t { speed 0.5 speed 0.4 taught { stop (0,0,0) } }", "twice", 1),
        ("trajectory t { taught speed 0.5 speed 0.4 { stop (0,0,0) } }", "twice", 1),
    ],
)
def test_semantic_errors_name_the_culprit(text: str, message: str, line: int) -> None:
    with pytest.raises(TDLError, match=message) as info:
        parse_tdl(text, "sem.tdl")
    assert not isinstance(info.value, TDLSyntaxError)
    assert info.value.filename == "sem.tdl"
    assert info.value.line == line


def test_keywords_can_be_names() -> None:
    doc = parse_tdl(
        "frame frame = (0,0,0)\ntrajectory speed { frame frame taught { stop (1,2,3) } }"
    )
    assert doc.names() == ("speed",)
    assert parse_tdl(print_tdl(doc)) == doc


def test_records_validate_in_python() -> None:
    with pytest.raises(ValidationError, match="not a valid name"):
        Trajectory("1abc", (Segment((Waypoint((0, 0, 0)),)),))
    with pytest.raises(ValidationError, match="fraction"):
        Segment((Waypoint((0, 0, 0)),), speed=0.0)
    with pytest.raises(ValidationError, match="3 coordinates"):
        Waypoint((0, 0))  # type: ignore[arg-type]
    with pytest.raises(ValidationError, match="unknown trajectory"):
        TDLDocument().trajectory("x")


def test_merge_detects_clashes() -> None:
    a = parse_tdl("trajectory t { taught { stop (0,0,0) } }")
    with pytest.raises(TDLError, match="defined twice"):
        a.merge(a)


def test_load_tdl_reports_missing_file(tmp_path: Path) -> None:
    with pytest.raises(TDLError, match="cannot read") as info:
        load_tdl(tmp_path / "missing.tdl")
    assert info.value.filename.endswith("missing.tdl")
    f = tmp_path / "bad.tdl"
    f.write_bytes(b"\xff\xfe")
    with pytest.raises(TDLError, match="UTF-8"):
        load_tdl(f)
    f.write_text("trajectory t { taught { via (0,0,0) } }")
    assert load_tdl(f).names() == ("t",)


@given(tdl_documents())
def test_print_parse_round_trip(doc: TDLDocument) -> None:
    text = print_tdl(doc)
    assert parse_tdl(text) == doc
    assert print_tdl(parse_tdl(text)) == text


@given(st.text(max_size=200))
def test_random_text_raises_only_tdl_errors(text: str) -> None:
    try:
        parse_tdl(text)
    except TDLError as exc:
        assert exc.line is not None and exc.line >= 1
        assert exc.column is not None and exc.column >= 1


@given(tdl_token_soup)
def test_token_soup_raises_only_tdl_errors(text: str) -> None:
    try:
        doc = parse_tdl(text)
    except TDLError as exc:
        assert exc.line is not None and exc.line >= 1
    else:
        assert isinstance(doc, TDLDocument)


def test_frame_record_roundtrip_by_hand() -> None:
    doc = TDLDocument(
        (Frame("a", (1.0, 2.0, 3.0)), Frame("b", (0.1, 0.2, 0.3), parent="a")),
        (
            Trajectory(
                "t",
                (Segment((Waypoint((0.0, 0.0, 0.0), stop=True),), "learned", 'say "hi"\n'),),
                "b",
            ),
        ),
    )
    assert parse_tdl(print_tdl(doc)) == doc
