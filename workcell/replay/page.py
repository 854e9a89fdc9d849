"""The replay as one self-contained HTML page, and its notebook view.

The page is a single file that works offline: the replay document
(:class:`~workcell.replay.data.ReplayData`) in a ``<script
type="application/json">`` element, and the viewer script (three.js and the
page's own code, bundled at build time into
``workcell/replay/static/replay.js``, docs/replay.md) inline. It shows the
cell in 3D (drag to turn, wheel to zoom), a time slider with play and
pause (also the space bar), a Gantt strip whose cursor follows the slider (click it to jump), the
zones coloured by state and the faults marked.


:func:`workcell.replay.data.build_replay` has an example of the whole path.
"""

from __future__ import annotations

import html
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

from multiarm.errors import InternalError, UsageError
from workcell.replay.data import STATE_COLOURS, Geometry, ReplayData, RunLike, build_replay

__all__ = ["render_html", "show", "viewer_script", "write_html"]

_STYLE = """
*{box-sizing:border-box}
body{margin:0;font:13px/1.4 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;color:#222;background:#fff}
header{padding:6px 12px;border-bottom:1px solid #ddd}
header h1{font-size:15px;margin:0}
header p{margin:2px 0 0;color:#555}
#view{position:relative;height:62vh;min-height:280px}
#view canvas{display:block}
#legend{position:absolute;top:8px;right:8px;background:rgba(255,255,255,.88);border:1px solid #ddd;
  border-radius:4px;padding:6px 8px;font-size:12px;max-width:45%}
#legend span.sw{display:inline-block;width:11px;height:11px;margin-right:4px;vertical-align:-1px;
  border:1px solid rgba(0,0,0,.4)}
#legend div{white-space:nowrap}
#controls{display:flex;gap:10px;align-items:center;padding:6px 12px;border-top:1px solid #ddd}
#time{flex:1}
#clock{font-variant-numeric:tabular-nums;min-width:12em;text-align:right}
#strip{padding:0 12px}
#gantt{display:block;cursor:pointer}
#status{padding:4px 12px 8px;color:#333;min-height:2.8em}
#replay-error{margin:8px 12px;padding:8px;border:1px solid #d62728;color:#a01010;background:#fff4f4}
"""

_MARK_GLYPH = {"X": "&#10006;", "*": "&#9733;", "D": "&#9670;", "v": "&#9660;", "s": "&#9632;",
               "o": "&#9679;", "^": "&#9650;", "P": "&#10010;"}  # fmt: skip


def viewer_script() -> str:
    """The bundled viewer (three.js and the page's code), as shipped in the package.

    Raises
    ------
    InternalError
        When the package was installed without it (a broken install).
    """
    try:
        return (resources.files("workcell.replay") / "static" / "replay.js").read_text("utf-8")
    except (OSError, ModuleNotFoundError) as exc:  # pragma: no cover - broken install
        raise InternalError(
            f"the replay viewer script is missing from the package ({exc}); "
            "rebuild it with 'make replay-js'"
        ) from None


def _legend(data: ReplayData) -> str:
    doc = data.document
    rows = ["<b>arms</b>"]
    for a in doc["arms"]:
        rows.append(
            f'<div><span class="sw" style="background:{a["colour"]}"></span>'
            f"{html.escape(a['name'])}</div>"
        )
    if doc["zones"]:
        rows.append("<b>zones</b>")
        for state, colour in STATE_COLOURS.items():
            what = {
                "free": "free",
                "occupied": "occupied (outline: the arm)",
                "moving": "an arm moving in a shared zone",
                "waiting": "an arm waiting at its border",
            }[state]
            rows.append(
                f'<div><span class="sw" style="background:{colour};opacity:.7"></span>{what}</div>'
            )
    on_arms = {f["kind"] for f in doc["faults"] if f["arm"] >= 0}
    if on_arms:
        rows.append("<b>arms with faults</b>")
        if "arm_failure" in on_arms:
            rows.append(
                '<div><span class="sw" style="background:#8c8c8c;border-color:#4a0000"></span>'
                "failed for good</div>"
            )
        if on_arms - {"arm_failure"}:
            rows.append(
                '<div><span class="sw" style="background:#d62728"></span>'
                "red flash: a fault on the arm</div>"
            )
    rows.append("<b>Gantt strip</b>")
    rows.append('<div><span class="sw" style="background:#888"></span>task as run</div>')
    rows.append(
        '<div><span class="sw" style="background:#ccc;height:4px;vertical-align:2px"></span>'
        "the plan</div>"
    )
    tasks = doc["tasks"]
    if any(t["status"] == "failed" and t["start"] is not None for t in tasks):
        rows.append('<div><span class="sw" style="background:#d62728"></span>failed task</div>')
    if any(t["status"] == "failed" and t["start"] is None for t in tasks):
        rows.append(
            '<div><span class="sw" style="background:#fde8e8;border:1px dashed #d62728"></span>'
            "failed task that never ran</div>"
        )
    for k in dict.fromkeys(f["kind"] for f in doc["faults"]):
        mark = doc["fault_marks"].get(k, doc["fault_marks"]["other"])
        glyph = _MARK_GLYPH.get(mark["symbol"], "&#10010;")
        rows.append(
            f'<div><span style="color:#d62728">{glyph}</span> {html.escape(mark["label"])}</div>'
        )
    return "\n".join(rows)


def render_html(data: ReplayData) -> str:
    """The self-contained page of a replay document (module docstring)."""
    doc = data.document
    s = doc["summary"]

    def sec(x: Any) -> str:
        return "-" if x is None else f"{float(x):.2f} s"

    facts = (
        f"planned makespan {sec(s['planned_makespan'])}, executed {sec(s['executed_makespan'])}; "
        f"{s['done_tasks']} tasks done, {s['failed_tasks']} failed; "
        f"{len(doc['arms'])} arms, {len(doc['zones'])} zones, {len(doc['faults'])} faults"
    )
    payload = data.to_json().replace("</", "<\\/")
    script = viewer_script().replace("</script", "<\\/script")
    title = html.escape(doc["title"])
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en"><head><meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width,initial-scale=1">\n'
        f'<meta name="generator" content="multiarm workcell.replay">\n'
        f"<title>{title}</title>\n<style>{_STYLE}</style></head>\n<body>\n"
        f"<header><h1>{title}</h1><p>{html.escape(facts)}</p></header>\n"
        '<div id="replay-error" hidden></div>\n'
        f'<div id="view"><div id="legend">{_legend(data)}</div></div>\n'
        '<div id="controls"><button id="play" type="button">Play</button>\n'
        '<input id="time" type="range" min="0" max="1" step="0.01" value="0" '
        'aria-label="time (s)">\n'
        '<select id="speed" aria-label="speed"><option value="0.5">0.5x</option>'
        '<option value="1" selected>1x</option><option value="2">2x</option>'
        '<option value="5">5x</option></select>\n'
        '<span id="clock"></span></div>\n'
        '<div id="strip"><canvas id="gantt"></canvas></div>\n'
        '<div id="status"></div>\n'
        f'<script type="application/json" id="multiarm-replay">{payload}</script>\n'
        f"<script>{script}</script>\n</body></html>\n"
    )


def write_html(
    result: RunLike | ReplayData,
    cell_or_compiled: Any,
    path: str | PathLike[str],
    *,
    rate: float = 25.0,
    max_frames: int = 1500,
    geometry: Geometry = "auto",
    title: str | None = None,
) -> Path:
    """Write the replay of a run as one self-contained HTML file.

    Parameters
    ----------
    result : workcell.SimResult or ReplayData
        The run, or a replay document already built (``cell_or_compiled``
        is then ignored and may be None).
    cell_or_compiled : Cell or CompiledCell or None
        The cell the run was simulated in (None: the run's own, if it keeps it).
    path : path-like
        The HTML file to write (its directory must exist).
    rate, max_frames, geometry, title
        As for :func:`~workcell.replay.data.build_replay`.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    UsageError
        Bad arguments, or a directory that does not exist.
    """
    p = Path(path)
    if p.is_dir():
        raise UsageError(f"{str(p)!r} is a directory, not an HTML file")
    if not p.parent.is_dir():
        raise UsageError(f"directory {str(p.parent)!r} does not exist")
    data = (
        result
        if isinstance(result, ReplayData)
        else build_replay(
            result,
            cell_or_compiled,
            rate=rate,
            max_frames=max_frames,
            geometry=geometry,
            title=title,
        )
    )
    p.write_text(render_html(data), encoding="utf-8")
    return p


def show(
    result: RunLike | ReplayData,
    cell_or_compiled: Any = None,
    *,
    height: int = 720,
    **options: Any,
) -> Any:
    """The replay for a notebook: an ``IPython.display.HTML`` holding the page
    in an ``<iframe srcdoc>`` (its script runs apart from the notebook's).

    Parameters
    ----------
    result, cell_or_compiled
        As for :func:`write_html`.
    height : int
        Pixels.
    **options
        ``rate``, ``max_frames``, ``geometry``, ``title`` (:func:`build_replay`).
    """
    from IPython.display import HTML

    data = (
        result
        if isinstance(result, ReplayData)
        else build_replay(result, cell_or_compiled, **options)
    )
    page = html.escape(render_html(data), quote=True)
    return HTML(  # type: ignore[no-untyped-call]
        f'<div><iframe srcdoc="{page}" style="width:100%;height:{int(height)}px;'
        'border:1px solid #ddd" sandbox="allow-scripts"></iframe></div>'
    )
