"""SDL (S2.5, S2.10): examples, the malformed corpus, round trips, random text."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from multiarm.errors import SDLError, SDLSyntaxError
from tests.strategies import sdl_token_soup, zone_maps
from zones import examples
from zones.geometry import HalfSpaces, MeshShape
from zones.model import ZoneMap
from zones.sdl import load_sdl, parse_sdl, print_sdl

CORPUS = sorted((Path(__file__).parent / "malformed").glob("*.sdl"))
HEADER = re.compile(r"# expect: (\w+) (\d+):(\d+) (.*)")


def test_corpus_is_large_enough() -> None:
    assert len(CORPUS) >= 30
    assert sum(p.name.startswith("s") for p in CORPUS) >= 15  # syntax
    assert sum(p.name.startswith("e") for p in CORPUS) >= 15  # semantic


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.stem)
def test_malformed_file_gives_the_intended_error(path: Path) -> None:
    text = path.read_text()
    m = HEADER.match(text.splitlines()[0])
    assert m, f"{path.name} lacks an '# expect:' header"
    cls_name, line, column, message = m.groups()
    cls = {"SDLSyntaxError": SDLSyntaxError, "SDLError": SDLError}[cls_name]
    with pytest.raises(SDLError) as info:
        load_sdl(path)
    err = info.value
    assert type(err) is cls, f"{path.name}: got {type(err).__name__}: {err}"
    assert (err.line, err.column) == (int(line), int(column)), str(err)
    assert err.filename == str(path)
    assert re.search(message, str(err)), str(err)
    assert str(err).startswith(f"{path}:{line}:{column}: ")


@pytest.mark.parametrize("name", examples.EXAMPLES)
def test_examples_parse_and_round_trip(name: str) -> None:
    zm = examples.load_example(name)
    assert zm.n_zones >= 2
    assert parse_sdl(print_sdl(zm)) == zm
    assert load_sdl(examples.example_path(name)) == zm


def test_supersigma_zones() -> None:
    zm = examples.load_example("supersigma")
    assert zm.zone("fixture").policy == "shared"
    assert zm.zone("fixture").speed_limit == 0.25
    assert isinstance(zm.zone("fixture").shape, HalfSpaces)
    assert zm.zones_at((1.0, 0.6, 0.2)) == ("fixture",)
    assert zm.zones_at((0.2, 0.3, 0.1)) == ("base_feeder",)
    assert zm.zones_at((1.0, 1.0, 0.1)) == ("fixture", "board")  # overlap is allowed
    assert zm.active_mask("sorting").sum() == 3
    assert zm.tools[0].name == "screwdriver"


def test_cell8_has_both_policies_and_phases() -> None:
    zm = examples.load_example("cell8")
    s = zm.summary()
    assert s["zones"] == 12 and s["exclusive"] >= 4 and s["shared"] >= 4
    assert s["active"] == 11  # 'overhead' starts inactive
    assert not zm.active_mask()[zm.zone_id("overhead")]
    assert zm.active_mask("maintenance")[zm.zone_id("overhead")]


def test_contains_matches_each_shape_and_bounds() -> None:
    zm = examples.load_example("cell8")
    rng = np.random.default_rng(1)
    lo, hi = np.asarray(zm.bounds[0]), np.asarray(zm.bounds[1])
    pts = rng.uniform(lo, hi, size=(5000, 3))
    got = zm.contains(pts)
    assert got.shape == (5000, 12)
    for z, zone in enumerate(zm.zones):
        assert np.array_equal(got[:, z], zone.shape.contains(pts))
    zb = zm.zone_bounds()
    for z in range(zm.n_zones):
        inside = pts[got[:, z]]
        assert np.all(inside >= zb[z, 0] - 1e-9) and np.all(inside <= zb[z, 1] + 1e-9)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        zm.contains(np.zeros((3, 2)))


def test_primitives_for_the_collision_layer() -> None:
    zm = examples.load_example("cell8")
    kinds = {p.kind for z in zm.zones for p in zm.primitives(z.name)}
    assert {"box", "cylinder", "sphere", "convex"} <= kinds
    for z in zm.zones:
        for p in zm.primitives(z.name):
            assert p.transform.shape == (4, 4)


def test_lookups_raise_our_errors() -> None:
    zm = examples.load_example("scara4")
    assert zm.zone_id(0) == 0
    with pytest.raises(SDLError, match="unknown zone 'nope'"):
        zm.zone_id("nope")
    with pytest.raises(SDLError, match="out of range"):
        zm.zone_id(99)
    with pytest.raises(SDLError, match="unknown tool"):
        zm.tool_id("hammer")
    with pytest.raises(SDLError, match="unknown phase"):
        zm.phase("night")


def test_mesh_zone_relative_to_file(tmp_path: Path) -> None:
    import trimesh

    box = trimesh.creation.box(extents=(0.4, 0.4, 0.4))
    box.apply_translation((1, 0.5, 0.5))
    (tmp_path / "meshes").mkdir()
    box.export(tmp_path / "meshes" / "fixture.stl")
    sdl = tmp_path / "cell.sdl"
    sdl.write_text('cell (0, 0, 0) (2, 1, 1)\nzone fx shared mesh "meshes/fixture.stl"\n')
    zm = load_sdl(sdl)
    assert isinstance(zm.zone("fx").shape, MeshShape)
    assert zm.zones_at((1, 0.5, 0.5)) == ("fx",)
    assert zm.zones_at((0.1, 0.1, 0.1)) == ()
    assert parse_sdl(print_sdl(zm), str(sdl)) == zm


def test_keywords_as_names() -> None:
    zm = parse_sdl(
        "cell (0,0,0) (1,1,1)\nwall x x = 0.5\nzone zone shared walls { +x }\nphase phase { zone }"
    )
    assert zm.zone_names() == ("zone",)
    assert parse_sdl(print_sdl(zm)) == zm


@settings(suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.data())
def test_print_parse_round_trip(data: st.DataObject) -> None:
    try:
        zm = data.draw(zone_maps())
    except SDLError:
        assume(False)  # the strategy drew a degenerate volume or a rack in an exclusive zone
        raise
    text = print_sdl(zm)
    back = parse_sdl(text)
    assert back == zm
    assert print_sdl(back) == text


@given(st.text(max_size=300))
def test_random_text_raises_only_sdl_errors(text: str) -> None:
    try:
        parse_sdl(text)
    except SDLError as exc:
        assert exc.line is not None and exc.line >= 1


@given(sdl_token_soup)
def test_token_soup_raises_only_sdl_errors(text: str) -> None:
    try:
        zm = parse_sdl(text)
    except SDLError as exc:
        assert exc.line is not None
    else:
        assert isinstance(zm, ZoneMap)


def test_load_errors(tmp_path: Path) -> None:
    with pytest.raises(SDLError, match="cannot read"):
        load_sdl(tmp_path / "none.sdl")
    bad = tmp_path / "bin.sdl"
    bad.write_bytes(b"\xff\xfe\xfd")
    with pytest.raises(SDLError, match="UTF-8"):
        load_sdl(bad)
