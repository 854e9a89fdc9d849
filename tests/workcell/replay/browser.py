"""Headless Debian Chromium driven by Playwright, for the replay's browser test.

Playwright never downloads a browser here: it starts the system's Chromium
(``/usr/bin/chromium``, Debian's ``chromium`` package; another with the
environment variable ``MULTIARM_CHROMIUM``) with the flags that work on a
machine with no network and no GPU (WebGL then runs on SwiftShader).

Run as a module it writes the screenshot of the documentation
(docs/images/replay.png)::

    .venv/bin/python -m tests.workcell.replay.browser docs/images/replay.png
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)


def chromium_path() -> str | None:
    """The Chromium executable, or None when there is none."""
    env = os.environ.get("MULTIARM_CHROMIUM")
    if env:
        return env if Path(env).is_file() else None
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    return None


def missing() -> str | None:
    """Why the browser test cannot run here, or None when it can."""
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "playwright is not installed (it is in the 'dev' extra: make .venv/.installed-stamp)"
    if chromium_path() is None:
        return "no Chromium: install Debian's package with 'apt-get install -y chromium'"
    return None


@contextmanager
def open_page(path: Path, width: int = 1100, height: int = 820, wait: bool = True) -> Iterator[Any]:
    """A Playwright page showing the HTML file ``path`` once the replay is
    ready (``wait=False``: once loaded, for a page that holds it in a frame).

    Raises AssertionError when the page reports an error or a script fails.
    """
    from playwright.sync_api import sync_playwright

    exe = chromium_path()
    assert exe is not None, missing()
    errors: list[str] = []
    with sync_playwright() as pw:  # each launch gets a fresh, empty profile
        browser = pw.chromium.launch(executable_path=exe, args=list(FLAGS))
        try:
            page = browser.new_page(viewport={"width": width, "height": height})
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(path.resolve().as_uri())
            if wait:
                page.wait_for_function(
                    "window.multiarmReplay && "
                    "(window.multiarmReplay.ready || window.multiarmReplay.error)",
                    timeout=20_000,
                )
                error = page.evaluate("window.multiarmReplay.error")
                assert error is None, f"the replay page failed: {error}"
            yield page
            assert not errors, f"script errors in the page: {errors}"
        finally:
            browser.close()


def main(argv: list[str]) -> int:
    """Write the screenshot of scara4's replay (greedy plan, a crash and an arm failure)."""
    from scheduler import solve
    from workcell import ArmFailure, Crash, compile_cell, load_example, simulate
    from workcell.replay import write_html

    out = Path(argv[0] if argv else "docs/images/replay.png")
    cc = compile_cell(load_example("scara4"))
    plan = solve(cc.problem, "greedy", seed=0).schedule
    run = simulate(cc, plan, faults=[Crash("se", 20.0, recovery=2.0), ArmFailure("nw", 60.0)])
    with tempfile.TemporaryDirectory() as tmp:
        page_path = write_html(run, cc, Path(tmp) / "replay.html")
        with open_page(page_path, 1100, 760) as page:
            page.locator("#time").fill("64")
            page.screenshot(path=str(out))
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
