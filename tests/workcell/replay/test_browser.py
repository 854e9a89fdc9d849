"""The replay page in a real headless browser (Debian's Chromium, Playwright).

Under CI (``CI=true``) a missing Chromium or Playwright fails the test; on a
developer's machine it is skipped with the reason (.ci/run installs Chromium).
"""

from __future__ import annotations

import colorsys
import io
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.workcell.replay import browser
from workcell.replay import build_replay, write_html


@pytest.fixture(scope="module")
def ready() -> None:
    why = browser.missing()
    if why is None:
        return
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(f"the browser test must run under CI: {why}")
    pytest.skip(why)


def _pixels(png: bytes) -> np.ndarray[Any, Any]:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=float) / 255.0


def _hue_share(img: np.ndarray[Any, Any], colour: str) -> int:
    """Pixels of the arm's hue (within 8 degrees), saturated and not dark: the
    arm's lit surfaces (shading changes value, not hue)."""
    r, g, b = (int(colour[i : i + 2], 16) / 255 for i in (1, 3, 5))
    h0 = colorsys.rgb_to_hsv(r, g, b)[0]
    mx, mn = img.max(-1), img.min(-1)
    sat = np.where(mx > 0, (mx - mn) / np.maximum(mx, 1e-9), 0.0)
    rr, gg, bb = img[..., 0], img[..., 1], img[..., 2]
    d = np.maximum(mx - mn, 1e-9)
    hue = (
        np.select(
            [mx == rr, mx == gg],
            [((gg - bb) / d) % 6, (bb - rr) / d + 2],
            (rr - gg) / d + 4,
        )
        / 6.0
    )
    close = np.abs((hue - h0 + 0.5) % 1.0 - 0.5) < 8 / 360
    return int(np.sum(close & (sat > 0.3) & (mx > 0.25)))


def test_replay_in_chromium(
    ready: None, scara4_cc: Any, scara4_faulty_run: Any, tmp_path: Path
) -> None:
    """Load the page, step the slider, and see the arms move in their colours."""
    data = build_replay(scara4_faulty_run, scara4_cc)
    path = write_html(data, None, tmp_path / "scara4.html")
    colours = {a["name"]: a["colour"] for a in data.document["arms"]}
    T, dt = data.duration, data.document["frames"]["dt"]
    with browser.open_page(path) as page:
        assert page.evaluate("window.multiarmReplay.duration") == pytest.approx(T)
        page.add_style_tag(content="#legend{display:none}")  # only the 3D view is counted
        view, gantt, slider = (
            page.locator("#view canvas"),
            page.locator("#gantt"),
            page.locator("#time"),
        )
        shots = {}
        for t in (0.0, 0.2 * T, 0.5 * T):
            slider.fill(f"{t:.3f}")  # the slider itself: its input event drives the page
            assert page.evaluate("window.multiarmReplay.time()") == pytest.approx(
                t, abs=dt
            )  # the step
            shots[t] = (_pixels(view.screenshot()), _pixels(gantt.screenshot()))
        (v0, _), (v1, g1), (v2, g2) = shots.values()
        moved = np.sum(np.abs(v1 - v2).max(-1) > 0.1)
        assert moved > 2000, f"only {moved} pixels of the 3D view changed between two times"
        assert np.sum(np.abs(g1 - g2).max(-1) > 0.1) > 50, "the Gantt cursor did not move"
        # at 0 s every zone is free (grey): the arms' hues are the arms' alone
        for arm, colour in colours.items():
            n = _hue_share(v0, colour)
            assert n > 1000, f"arm {arm} ({colour}) shows in {n} pixels only"
        # nw fails for good at 60 s: it turns grey
        nw = colours["nw"]
        assert _hue_share(v2, nw) < 0.1 * _hue_share(v0, nw)
        # se crashes at 20 s: it flashes the faults' red for a second
        red = []
        for t in (19.9, 20.4):
            slider.fill(f"{t}")
            red.append(_hue_share(_pixels(view.screenshot()), "#d62728"))
        assert red[1] > 1000 and red[1] > 5 * red[0], f"red pixels before and in the flash: {red}"
        # play runs the clock on, pause stops it
        t_before = page.evaluate("window.multiarmReplay.time()")
        page.locator("#play").click()
        page.wait_for_function(f"window.multiarmReplay.time() > {t_before + 0.05}", timeout=10_000)
        page.locator("#play").click()
        t_paused = page.evaluate("window.multiarmReplay.time()")
        page.wait_for_timeout(200)
        assert page.evaluate("window.multiarmReplay.time()") == t_paused
        # the faults are marked in the Gantt strip and listed in the legend
        legend = page.locator("#legend").inner_text()
        assert "crash" in legend and "arm failure" in legend


def test_urdf_arms_as_meshes_in_chromium(ready: None, tmp_path: Path) -> None:
    """urdf_cell: two UR5 and a Panda drawn as their links' collision meshes."""
    from scheduler import solve
    from workcell import compile_cell, load_example, simulate

    cc = compile_cell(load_example("urdf_cell"))
    run = simulate(cc, solve(cc.problem, "greedy", seed=0).schedule)
    data = build_replay(run, cc, max_frames=300)
    assert {b["kind"] for b in data.document["bodies"]} == {"mesh"}
    path = write_html(data, None, tmp_path / "urdf_cell.html")
    T = data.duration
    with browser.open_page(path) as page:
        page.add_style_tag(content="#legend{display:none}")
        view = page.locator("#view canvas")
        shots = []
        for t in (0.0, 0.3 * T):
            page.locator("#time").fill(f"{t:.3f}")
            shots.append(_pixels(view.screenshot()))
        moved = np.sum(np.abs(shots[0] - shots[1]).max(-1) > 0.1)
        assert moved > 500, f"only {moved} pixels of the 3D view changed"
        for a in data.document["arms"]:
            n = _hue_share(shots[0], a["colour"])
            assert n > 500, f"arm {a['name']} ({a['colour']}) shows in {n} pixels only"
        # the screwdriver stands at its rack, then rides on the UR5 holding it
        tool = data.document["tools"][0]
        held = tool["held"][0]
        rack = np.asarray(tool["rack"])
        page.locator("#time").fill(f"{0.5 * held['start']:.3f}")
        free = page.evaluate(f"window.multiarmReplay.toolAt({tool['name']!r})")
        assert free["arm"] == -1 and np.allclose(free["position"], rack)
        mid = 0.5 * (held["start"] + held["end"])
        page.locator("#time").fill(f"{mid:.3f}")
        carried = page.evaluate(f"window.multiarmReplay.toolAt({tool['name']!r})")
        assert carried["arm"] == held["arm"]
        t_now = page.evaluate("window.multiarmReplay.time()")
        tip = data.document["arms"][held["arm"]]["tip"]
        path = data.poses()[:, tip, :3]
        want = [np.interp(t_now, data.times(), path[:, k]) for k in range(3)]
        assert np.allclose(carried["position"], want, atol=2e-3)
        assert np.linalg.norm(np.asarray(carried["position"]) - rack) > 0.05


def test_notebook_view_runs_in_its_frame(
    ready: None, scara4_cc: Any, scara4_run: Any, tmp_path: Path
) -> None:
    """workcell.replay.show: the page inside a sandboxed iframe starts and plays."""
    from workcell.replay import show

    shown = show(scara4_run, scara4_cc, max_frames=100, height=600)
    host = tmp_path / "notebook.html"
    host.write_text(f"<!DOCTYPE html><html><body><h3>a notebook</h3>{shown.data}</body></html>")
    with browser.open_page(host, wait=False) as page:
        frame = page.frames[1]
        frame.wait_for_function(
            "window.multiarmReplay && (window.multiarmReplay.ready || window.multiarmReplay.error)",
            timeout=20_000,
        )
        assert frame.evaluate("window.multiarmReplay.error") is None
        frame.locator("#view canvas").click()  # focus in the frame, then the space bar plays
        page.keyboard.press(" ")
        frame.wait_for_function("window.multiarmReplay.time() > 0.05", timeout=10_000)
