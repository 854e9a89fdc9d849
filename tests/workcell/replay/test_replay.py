"""The replay document and page (workcell.replay) without a browser."""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from multiarm.errors import UsageError, ValidationError
from workcell import load_example
from workcell.replay import (
    REPLAY_FILE,
    ReplayData,
    build_replay,
    load_replay,
    render_html,
    save_replay,
    show,
    write_html,
)
from workcell.replay import command as view_command

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def data(scara4_cc: Any, scara4_faulty_run: Any) -> ReplayData:
    return build_replay(scara4_faulty_run, scara4_cc, max_frames=400)


def test_poses_are_the_arms_shapes_at_the_sampled_times(
    data: ReplayData, scara4_cc: Any, scara4_faulty_run: Any
) -> None:
    """Every body's stored pose is its shape's world pose for the run's joints
    at that time, to the quantisation: 1 step of the int16 grid, 1e-4 rad."""
    times = data.times()
    assert len(times) == 400 and times[0] == 0 and times[-1] == pytest.approx(data.duration)
    joints = scara4_faulty_run.joints(times)
    want = np.concatenate(
        [scara4_cc.cell.arm(a).shape_transforms(joints[a]) for a in data.arm_names], axis=1
    )
    got = data.poses()
    assert got.shape == (400, want.shape[1], 7)
    step = np.asarray(data.document["frames"]["scale"])
    assert np.all(np.abs(got[..., :3] - want[..., :3, 3]) <= step * 0.51 + 1e-9)
    r_got = Rotation.from_quat(got[..., 3:].reshape(-1, 4))
    r_want = Rotation.from_matrix(want[..., :3, :3].reshape(-1, 3, 3))
    assert np.max((r_got.inv() * r_want).magnitude()) < 1e-4
    # quaternions stay in one hemisphere from frame to frame (the page interpolates)
    q = got[..., 3:]
    assert np.all(np.einsum("nbk,nbk->nb", q[1:], q[:-1]) > 0)
    # the arms do move during the run
    assert np.ptp(got[..., :3], axis=0).max() > 0.1


def test_zone_states_follow_the_run(data: ReplayData, scara4_faulty_run: Any) -> None:
    doc = data.document
    names = [z["name"] for z in doc["zones"]]
    occupied = {
        (names[s["zone"]], data.arm_names[s["arm"]], s["start"], s["end"])
        for s in doc["zone_states"]
        if s["state"] == "occupied"
    }
    res = scara4_faulty_run.reservations_frame()
    zone_rows = res[res["kind"] == "zone"]
    assert occupied == {
        (r.resource, r.arm, float(r.start), float(r.end)) for r in zone_rows.itertuples()
    }
    moving = [s for s in doc["zone_states"] if s["state"] == "moving"]
    assert len(moving) == int(np.sum(res["kind"] == "move"))
    # waiting: from the coordinator's sleep to its wake-up of that arm, for that zone
    sleeps = {(e.arm, e.zone, e.time) for e in scara4_faulty_run.trace if e.kind == "sleep"}
    wakes = {(e.arm, e.zone, e.time) for e in scara4_faulty_run.trace if e.kind == "wake"}
    waiting = [s for s in doc["zone_states"] if s["state"] == "waiting"]
    assert waiting, "scara4's greedy plan has arms waiting at zone borders"
    for s in waiting:
        arm, zone = data.arm_names[s["arm"]], names[s["zone"]]
        assert (arm, zone, s["start"]) in sleeps and (arm, zone, s["end"]) in wakes
    # the SDL zones have solids; space-grid blocks have one box of the grid's side
    sdl = set(load_example("scara4").zone_map.zone_names())
    for z in doc["zones"]:
        assert z["grid"] == (z["name"] not in sdl)
        if z["name"] in sdl:
            assert z["solids"]
        elif z["name"].startswith("grid_"):
            (box,) = z["solids"]
            assert box["kind"] == "box" and box["size"] == pytest.approx([0.3] * 3)


def test_faults_tasks_and_colours(data: ReplayData) -> None:
    doc = data.document
    faults = [(f["kind"], data.arm_names[f["arm"]], f["time"]) for f in doc["faults"]]
    assert faults == [("crash", "se", 20.0), ("arm_failure", "nw", 60.0)]
    assert set(doc["fault_marks"]) >= {"crash", "arm_failure", "other"}
    assert len(doc["tasks"]) == 20
    assert all(t["start"] is not None and t["end"] > t["start"] for t in doc["tasks"])
    from workcell.style import arm_colours

    rgba = arm_colours(list(data.arm_names))
    for a in doc["arms"]:
        r, g, b = (int(a["colour"][i : i + 2], 16) for i in (1, 3, 5))
        assert (r, g, b) == tuple(round(255 * c) for c in rgba[a["name"]][:3])


def test_document_round_trips_through_a_run_directory(
    data: ReplayData, scara4_cc: Any, scara4_run: Any, tmp_path: Path
) -> None:
    text = data.to_json()
    json.loads(text)  # strict JSON: no NaN or Infinity
    assert ReplayData.from_json(text) == data
    path = save_replay(scara4_run, scara4_cc, tmp_path / "run", max_frames=50)
    assert path == tmp_path / "run" / REPLAY_FILE
    back = load_replay(tmp_path / "run")
    assert back.n_frames == 50 and back == load_replay(path)
    assert back != data


def test_bad_replay_documents_name_the_culprit(data: ReplayData, tmp_path: Path) -> None:
    with pytest.raises(UsageError, match=r"holds no replay\.json"):
        load_replay(tmp_path)
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ValidationError, match=r"bad\.json: not JSON"):
        load_replay(bad)
    doc = json.loads(data.to_json())
    doc["format"] = "multiarm.replay/0"
    with pytest.raises(ValidationError, match=r"replay\.format: expected 'multiarm\.replay/1'"):
        ReplayData.from_json(json.dumps(doc))
    doc = json.loads(data.to_json())
    del doc["frames"]["poses"]
    with pytest.raises(ValidationError, match=r"frames\.poses: missing"):
        ReplayData.from_json(json.dumps(doc))
    doc = json.loads(data.to_json())
    doc["bodies"][0]["arm"] = 9
    with pytest.raises(ValidationError, match=r"bodies\[0\]\.arm: no arm 9"):
        ReplayData.from_json(json.dumps(doc))
    doc = json.loads(data.to_json())
    doc["tools"][0]["held"][0]["arm"] = 7
    with pytest.raises(ValidationError, match=r"tools\[0\]\.held\[0\]\.arm: no arm 7"):
        ReplayData.from_json(json.dumps(doc))
    doc = json.loads(data.to_json())
    del doc["tools"][1]["rack"]
    with pytest.raises(ValidationError, match=r"tools\[1\]: needs a 'rack'"):
        ReplayData.from_json(json.dumps(doc))
    doc = json.loads(data.to_json())
    doc["frames"]["n"] += 1
    with pytest.raises(ValidationError, match=r"frames\.poses: \d+ values, expected"):
        ReplayData.from_json(json.dumps(doc)).poses()


def test_bad_arguments(scara4_run: Any, scara4_cc: Any, tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="not the cell's"):
        build_replay(scara4_run, load_example("supersigma"))
    with pytest.raises(UsageError, match="max_frames"):
        build_replay(scara4_run, scara4_cc, max_frames=1)
    with pytest.raises(UsageError, match="rate"):
        build_replay(scara4_run, scara4_cc, rate=float("nan"))
    with pytest.raises(UsageError, match="geometry"):
        build_replay(scara4_run, scara4_cc, geometry="wire")  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="Cell or a CompiledCell"):
        build_replay(scara4_run, object())
    if not hasattr(scara4_run, "compiled") and not hasattr(scara4_run, "cell"):
        with pytest.raises(UsageError, match="does not keep its cell"):
            build_replay(scara4_run, None)
    with pytest.raises(UsageError, match="does not exist"):
        write_html(scara4_run, scara4_cc, tmp_path / "no" / "x.html")


def test_page_is_self_contained_and_small(data: ReplayData, tmp_path: Path) -> None:
    page = render_html(data)
    assert page.startswith("<!DOCTYPE html>")
    # nothing is fetched: no external script, stylesheet, image or module
    assert not re.search(r"<(script|link|img|iframe)[^>]+(src|href)=", page)
    assert "import(" not in page.split("<script>", 1)[1][:200]
    # the document in the page is the replay's, and the page keeps it parseable
    m = re.search(
        r'<script type="application/json" id="multiarm-replay">(.*?)</script>', page, re.S
    )
    assert m is not None
    assert ReplayData.from_json(m.group(1).replace("<\\/", "</")) == data
    assert len(page.encode()) < 3e6
    assert "crash" in page and "arm failure" in page  # the legend names the faults shown


def test_sim_result_writes_its_own_page(
    scara4_faulty_run: Any, data: ReplayData, tmp_path: Path
) -> None:
    """``SimResult.to_html(path)`` (issue 19): the run keeps its compiled cell,
    so the page needs no other argument and holds the same replay."""
    page = scara4_faulty_run.to_html(tmp_path / "run.html", max_frames=400)
    text = page.read_text()
    m = re.search(
        r'<script type="application/json" id="multiarm-replay">(.*?)</script>', text, re.S
    )
    assert m is not None
    assert ReplayData.from_json(m.group(1).replace("<\\/", "</")) == data


def test_view_command_writes_the_page(
    scara4_run: Any, scara4_cc: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    save_replay(scara4_run, scara4_cc, tmp_path, max_frames=60)
    parser = argparse.ArgumentParser()
    view_command.add_arguments(parser)
    assert view_command.run(parser.parse_args([str(tmp_path)])) == 0
    page = tmp_path / "replay.html"
    assert page.is_file() and str(page) in capsys.readouterr().out
    out = tmp_path / "elsewhere.html"
    assert (
        view_command.run(parser.parse_args([str(tmp_path / REPLAY_FILE), "--out", str(out)])) == 0
    )
    assert out.read_text() == page.read_text()
    with pytest.raises(UsageError, match=r"must end in \.html"):
        view_command.run(parser.parse_args([str(tmp_path), "--out", str(tmp_path / "x.txt")]))
    (tmp_path / "empty").mkdir()
    with pytest.raises(UsageError, match=r"holds no replay\.json"):
        view_command.run(parser.parse_args([str(tmp_path / "empty")]))
    with pytest.raises(UsageError, match="no such file or directory"):
        view_command.run(parser.parse_args([str(tmp_path / "nowhere")]))


def test_notebook_view(data: ReplayData) -> None:
    shown = show(data, height=500)
    assert shown.data.startswith("<div><iframe srcdoc=") and "height:500px" in shown.data
    assert "&lt;!DOCTYPE html&gt;" in shown.data


def test_bundle_is_the_pinned_three() -> None:
    """The committed viewer bundles the three.js that package-lock.json pins,
    with its licence (CI rebuilds it with 'make replay-js' and compares)."""
    lock = json.loads((ROOT / "workcell/replay/web/package-lock.json").read_text())
    version = lock["packages"]["node_modules/three"]["version"]
    revision = version.split(".")[1]
    static = ROOT / "workcell/replay/static"
    bundle = (static / "replay.js").read_text()
    assert f'window.__THREE__="{revision}"' in bundle
    assert "SPDX-License-Identifier: MIT" in bundle
    assert "MIT License" in (static / "three-LICENSE.txt").read_text()


def test_planned_arm_is_the_given_plans(data: ReplayData, scara4_faulty_run: Any) -> None:
    """After nw fails and its tasks are re-solved onto other arms, a task's
    plan strip stays on the arm the given plan chose."""
    plan = scara4_faulty_run.schedule.to_dataframe(scara4_faulty_run.problem)
    planned = {r.task: r.arm for r in plan.itertuples()}
    moved = 0
    for t in data.document["tasks"]:
        assert data.arm_names[t["planned_arm"]] == planned[t["task"]]
        moved += t["planned_arm"] != t["arm"]
    assert moved > 0, "nw's tasks ran on other arms"


def test_tools_stand_at_their_racks_and_follow_the_holders_reservations(
    data: ReplayData, scara4_cc: Any, scara4_faulty_run: Any
) -> None:
    """Every tool of the zone map is in the document at its rack, held exactly
    in the run's tool reservations (clipped to the replay), and every arm
    names its tip: a body on its deepest kinematic frame."""
    zm = scara4_cc.cell.zone_map
    tools = {t["name"]: t for t in data.document["tools"]}
    assert set(tools) == {t.name for t in zm.tools}
    for t in zm.tools:
        assert tools[t.name]["rack"] == pytest.approx(list(t.rack))
    index = {a: i for i, a in enumerate(data.arm_names)}
    want: dict[str, list[tuple[int, float, float]]] = {name: [] for name in tools}
    for row in scara4_faulty_run.reservations_frame().to_dict("records"):
        if row["kind"] == "tool" and np.isfinite(row["start"]):
            end = min(row["end"], data.duration) if np.isfinite(row["end"]) else data.duration
            if end > row["start"]:
                want[row["resource"]].append((index[row["arm"]], row["start"], end))
    assert sum(len(w) for w in want.values()) >= 2  # scara4's screws and presses use them
    for name, t in tools.items():
        got = np.array([(h["arm"], h["start"], h["end"]) for h in t["held"]]).reshape(-1, 3)
        expect = np.array(sorted(want[name], key=lambda x: (x[1], x[2]))).reshape(-1, 3)
        assert got.shape == expect.shape and np.allclose(got, expect, rtol=0, atol=1e-9)
    bodies = data.document["bodies"]
    for a, entry in enumerate(data.document["arms"]):
        arm = scara4_cc.cell.arm(entry["name"])
        deepest = max(s.frame for s in arm.shapes)
        tip = bodies[entry["tip"]]
        assert tip["arm"] == a
        assert next(s for s in arm.shapes if s.name == tip["name"]).frame == deepest
    # a document written before tools were drawn still loads
    doc = json.loads(data.to_json())
    del doc["tools"]
    assert ReplayData.from_json(json.dumps(doc)).document.get("tools") is None
