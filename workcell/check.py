"""``multiarm check``: validate files, and explain a cell.

:func:`explain_cell` compiles a cell and says, per arm, its kind, the tasks
it can do and, for every task it cannot do, why (``capability``, ``tool``,
``reach``, ``orientation``, ``collision at rest``, from
:attr:`workcell.CompiledCell.rejected`); which tasks and arms use each SDL
zone and each tool; and warnings for what compiles but is likely a mistake:

* an arm that can do no task;
* two arms that collide at their start joints (FCL, through
  :class:`workcell.geometry.world.CollisionWorld`);
* a name used both as a zone and as a tool;
* a tool that tasks use or arms mount but no SDL ``tool`` declares.

:func:`check_files` is the command: one report a file, text or JSON
(``--json``), exit status 0 when every file is clean or has warnings only,
1 on an error.

A built-in cell's name (``supersigma``, ``scara4``, ``cell8``) is explained
like a cell file. A ``.toml`` file is a task set when its top level holds a ``tasks`` list or
a ``format`` tag, and a cell file otherwise, so that an empty, undecodable
or broken cell file is reported as the cell file it was meant to be
(``cell.toml:3:9: TOML syntax error: ...``).

Examples
--------
>>> from workcell import load_example
>>> report = explain_cell(load_example("supersigma"))
>>> [(a.name, a.kind, len(a.tasks)) for a in report.arms]
[('left', 'gantry', 10), ('right', 'gantry', 9)]
>>> report.arms[1].rejected[0].category
'capability'
>>> report.warnings
()
"""

from __future__ import annotations

import json
import sys
import tomllib
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, TextIO

from multiarm.errors import MultiarmError
from workcell.cell import Cell

__all__ = [
    "ArmReport",
    "CellReport",
    "FileReport",
    "Rejection",
    "ToolReport",
    "ZoneReport",
    "check_file",
    "check_files",
    "explain_cell",
    "reason_category",
]


@dataclass(frozen=True, slots=True)
class Rejection:
    """Why an arm cannot do a task: the compile's reason and its category."""

    task: str
    category: str
    reason: str


@dataclass(frozen=True, slots=True)
class ArmReport:
    """One arm: its kind, the tasks it can do, and why not the others."""

    name: str
    kind: str
    tasks: tuple[str, ...]
    rejected: tuple[Rejection, ...]


@dataclass(frozen=True, slots=True)
class ZoneReport:
    """An SDL zone: its policy, the tasks whose modes enter it, and their arms."""

    name: str
    policy: str
    tasks: tuple[str, ...]
    arms: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class ToolReport:
    """A tool: declared by the SDL or not, the tasks using it, the arms mounting it."""

    name: str
    declared: bool
    tasks: tuple[str, ...]
    arms: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class CellReport:
    """What :func:`explain_cell` found.

    Attributes
    ----------
    name : str
        The cell's name.
    arms : tuple of ArmReport
        In the cell's order; empty when the compile failed.
    zones, tools : tuples of ZoneReport, ToolReport
    warnings : tuple of str
    error : str or None
        Why the cell does not compile (then ``arms`` list kinds only).
    n_tasks, n_modes : int
    """

    name: str
    arms: tuple[ArmReport, ...]
    zones: tuple[ZoneReport, ...]
    tools: tuple[ToolReport, ...]
    warnings: tuple[str, ...]
    error: str | None
    n_tasks: int
    n_modes: int


@dataclass(frozen=True, slots=True)
class FileReport:
    """One checked file: its kind, a one-line summary, an error, and a cell's report."""

    file: str
    kind: str
    ok: bool
    summary: str = ""
    error: str | None = None
    cell: CellReport | None = None


def reason_category(reason: str) -> str:
    """The category of a compile's rejection reason.

    One of ``"capability"``, ``"tool"``, ``"collision at rest"``,
    ``"orientation"``, ``"collision"`` and ``"reach"`` (joint limits,
    distance, no IK solution).

    Examples
    --------
    >>> reason_category("lacks capability 'force_sensor'")
    'capability'
    >>> reason_category("would hit arm 'b' resting at its start joints")
    'collision at rest'
    """
    text = reason.lower()
    if "lacks capability" in text:
        return "capability"
    if "cannot mount tool" in text:
        return "tool"
    if "resting at its start" in text:
        return "collision at rest"
    if "tool vertical" in text or "tilts" in text or "no wrist" in text or "yaw" in text:
        return "orientation"
    if "collid" in text or "hits" in text or "wall" in text:
        return "collision"
    return "reach"


def _start_overlaps(cell: Cell) -> list[str]:
    from workcell.geometry.world import CollisionWorld

    world = CollisionWorld()
    for arm, q in zip(cell.arms, cell.start, strict=True):
        world.add_arm(arm, q=q)
    out = []
    arms = cell.arms
    for i, a in enumerate(arms):
        for b in arms[i + 1 :]:
            pairs = world.colliding_pairs(a.name, b.name)
            if pairs:
                shapes = ", ".join(f"{x} / {y}" for x, y in pairs[:3])
                out.append(
                    f"arms {a.name!r} and {b.name!r} collide at their start joints ({shapes}): "
                    "give one of them a 'start' away from the other"
                )
    return out


def _static_warnings(cell: Cell) -> list[str]:
    zm = cell.zone_map
    zone_names = set(zm.zone_names())
    declared = {t.name for t in zm.tools}
    warnings = _start_overlaps(cell)
    for name in sorted(zone_names & declared):
        warnings.append(f"{name!r} is the name of a zone and of a tool: rename one of them")
    used = {t.tool for t in cell.taskset.tasks if t.tool is not None}
    for name in sorted(used - declared):
        users = [t.id for t in cell.taskset.tasks if t.tool == name]
        warnings.append(
            f"tool {name!r} (of tasks {', '.join(users)}) is declared by no SDL 'tool': "
            "no rack, and two arms may use it at once"
        )
    mounted = {tool for arm in cell.arms for tool in arm.tools}
    for name in sorted(mounted - declared - used):
        arms = [a.name for a in cell.arms if name in a.tools]
        warnings.append(
            f"tool {name!r} mounted by arms {', '.join(arms)} is declared by no SDL 'tool' "
            "and used by no task"
        )
    return warnings


def explain_cell(cell: Cell) -> CellReport:
    """Compile ``cell`` and explain it (module docstring).

    Never raises for a cell that does not compile: the compile's error is
    the report's ``error``.
    """
    from workcell.compile import compile_cell

    warnings = _static_warnings(cell)
    zm = cell.zone_map
    declared = {t.name for t in zm.tools}
    task_tools: dict[str, list[str]] = {}
    for t in cell.taskset.tasks:
        if t.tool is not None:
            task_tools.setdefault(t.tool, []).append(t.id)
    names = sorted(declared | set(task_tools))
    tools = tuple(
        ToolReport(
            n,
            n in declared,
            tuple(task_tools.get(n, ())),
            tuple(a.name for a in cell.arms if n in a.tools),
        )
        for n in names
    )
    n_tasks = len(cell.taskset.tasks)
    try:
        cc = compile_cell(cell)
    except MultiarmError as exc:
        zones = tuple(ZoneReport(z.name, z.policy, (), ()) for z in zm.zones)
        return CellReport(cell.name, (), zones, tools, tuple(warnings), str(exc), n_tasks, 0)
    can: dict[str, list[str]] = {a.name: [] for a in cell.arms}
    zone_tasks: dict[str, set[str]] = {z.name: set() for z in zm.zones}
    zone_arms: dict[str, set[str]] = {z.name: set() for z in zm.zones}
    zone_names = cc.problem.zone_names
    for mode in cc.modes:
        can[mode.arm].append(mode.task)
        for w in mode.windows:
            zname = w.zone if isinstance(w.zone, str) else zone_names[int(w.zone)]
            if zname in zone_tasks:
                zone_tasks[zname].add(mode.task)
                zone_arms[zname].add(mode.arm)
    order = {t.id: i for i, t in enumerate(cell.taskset.tasks)}
    arms = []
    for arm in cell.arms:
        rejected = tuple(
            Rejection(task, reason_category(why), why)
            for (task, a), why in sorted(cc.rejected.items(), key=lambda kv: order[kv[0][0]])
            if a == arm.name
        )
        tasks = tuple(sorted(dict.fromkeys(can[arm.name]), key=order.__getitem__))
        arms.append(ArmReport(arm.name, arm.kind, tasks, rejected))
        if not tasks:
            cats = sorted({r.category for r in rejected})
            warnings.append(
                f"arm {arm.name!r} can do no task ({', '.join(cats) or 'no task'}): "
                "see its 'cannot do' list"
            )
    zones = tuple(
        ZoneReport(
            z.name,
            z.policy,
            tuple(sorted(zone_tasks[z.name], key=order.__getitem__)),
            tuple(a.name for a in cell.arms if a.name in zone_arms[z.name]),
        )
        for z in zm.zones
    )
    return CellReport(
        cell.name, tuple(arms), zones, tools, tuple(warnings), None, n_tasks, cc.problem.n_modes
    )


# ------------------------------------------------------------------ files


def _is_task_set(path: Path) -> bool:
    """A TOML file whose top level holds a ``tasks`` list or a ``format`` tag."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False
    return isinstance(data.get("tasks"), list) or "format" in data


def _check_scheduling(path: Path, kind: str, problem_name: str | None) -> str:
    """Check a problem JSON, a schedule or an FJSP file (recognised by content)."""
    from multiarm.errors import UsageError
    from scheduler import load_problem, load_schedule, lower_bound, read_fjsp, validate

    if kind == "fjsp":
        p = read_fjsp(path)
        return f"FJSP instance: {p.n_arms} machines, {p.n_tasks} operations, {p.n_modes} modes"
    if kind == "problem":
        p = load_problem(path)
        return (
            f"problem {p.name!r}: {p.n_arms} arms, {p.n_tasks} tasks, {p.n_modes} modes, "
            f"{p.n_zones} zones, lower bound {lower_bound(p):.6g}"
        )
    if problem_name is None:
        raise UsageError(
            f"{path}: a schedule is checked against its problem: add --problem PROBLEM"
        )
    problem = load_schedulable(problem_name)
    s = load_schedule(path, problem)
    return f"schedule of {s.n_tasks} tasks, valid, makespan {validate(problem, s):.6g}"


def _kind(path: Path) -> str:
    from scheduler import detect_format
    from workcell.cell import EXAMPLES

    if not path.exists() and str(path) in EXAMPLES:
        return "builtin cell"

    kind = detect_format(path) if path.is_file() else None
    if kind is not None:
        return kind
    suffix = path.suffix.lower()
    if suffix == ".fjs":
        return "fjsp"
    if suffix == ".toml":
        return "taskset" if _is_task_set(path) else "cell"
    return {".tdl": "tdl", ".sdl": "sdl", ".json": "taskset"}.get(suffix, "unknown")


def check_file(path: Path, problem_name: str | None = None) -> FileReport:
    """Check one file (module docstring); never raises for a bad file."""
    kind = _kind(path)
    try:
        if kind in ("fjsp", "problem", "schedule"):
            return FileReport(str(path), kind, True, _check_scheduling(path, kind, problem_name))
        if kind in ("cell", "builtin cell"):
            from workcell.cell import load_cell, load_example

            cell = load_example(str(path)) if kind == "builtin cell" else load_cell(path)
            report = explain_cell(cell)
            summary = (
                f"cell {cell.name!r}: {len(cell.arms)} arms, {report.n_tasks} tasks, "
                f"{report.n_modes} modes, {cell.zone_map.n_zones} zones, "
                f"{len(report.tools)} tools"
            )
            err = None if report.error is None else f"{path}: {report.error}"
            return FileReport(str(path), kind, err is None, summary, err, report)
        if kind == "tdl":
            from tasklib import load_tdl

            doc = load_tdl(path)
            summary = f"{len(doc.trajectories)} trajectories, {len(doc.frames)} frames"
            return FileReport(str(path), kind, True, summary)
        if kind == "taskset":
            from tasklib import load_taskset

            s = load_taskset(path).summary()
            summary = (
                f"task set {s['name']!r}: {s['tasks']} tasks, {s['parts']} parts, "
                f"depth {s['depth']}"
            )
            return FileReport(str(path), kind, True, summary)
        if kind == "sdl":
            from zones import load_sdl

            z = load_sdl(path).summary()
            summary = (
                f"{z['zones']} zones ({z['exclusive']} exclusive, {z['shared']} shared), "
                f"{z['walls']} walls, {z['tools']} tools, {z['phases']} phases"
            )
            return FileReport(str(path), kind, True, summary)
        raise MultiarmError(
            f"{path}: unknown file type {path.suffix.lower()!r} "
            "(known: .tdl, .sdl, .toml, .json, .fjs)"
        )
    except MultiarmError as exc:
        return FileReport(str(path), kind, False, error=str(exc))


def _join(names: Sequence[str], empty: str = "-") -> str:
    return ", ".join(names) if names else empty


def _print_cell(r: CellReport, out: TextIO) -> None:
    if r.arms:
        width = max(len(a.name) for a in r.arms)
        print("  arms:", file=out)
        for a in r.arms:
            print(
                f"    {a.name.ljust(width)}  {a.kind:<7} {len(a.tasks)}/{r.n_tasks} tasks: "
                f"{_join(a.tasks, 'none')}",
                file=out,
            )
        rejected = [(a.name, x) for a in r.arms for x in a.rejected]
        if rejected:
            print("  cannot do:", file=out)
            for name, x in rejected:
                print(f"    {name} {x.task} ({x.category}): {x.reason}", file=out)
    if r.zones:
        print("  zones:", file=out)
        for z in r.zones:
            print(
                f"    {z.name} ({z.policy}): tasks {_join(z.tasks)}; arms {_join(z.arms)}",
                file=out,
            )
    if r.tools:
        print("  tools:", file=out)
        for t in r.tools:
            state = "declared" if t.declared else "NOT declared in the SDL"
            print(
                f"    {t.name} ({state}): tasks {_join(t.tasks)}; mounted by {_join(t.arms)}",
                file=out,
            )
    for w in r.warnings:
        print(f"  warning: {w}", file=out)


def check_files(
    paths: Sequence[str], problem_name: str | None = None, as_json: bool = False
) -> int:
    """The ``check`` command: report every file; 0 when all are ok (warnings allowed), else 1.

    Text goes to stdout (errors also to stderr as ``error: file:line:col:
    message``); with ``as_json`` one JSON document ``{"ok": ..., "files":
    [...]}`` goes to stdout, each file as :class:`FileReport` fields.
    """
    reports = [check_file(Path(p), problem_name) for p in paths]
    ok = all(r.ok for r in reports)
    if as_json:
        doc: dict[str, Any] = {"ok": ok, "files": [asdict(r) for r in reports]}
        print(json.dumps(doc, indent=2))
        return 0 if ok else 1
    for r in reports:
        n = len(r.cell.warnings) if r.cell is not None else 0
        if r.ok:
            status = f"ok with {n} warning{'s' * (n != 1)}" if n else "ok"
            print(f"{r.file}: {status} ({r.summary})")
        elif r.cell is not None:
            print(f"{r.file}: {r.summary}")
        if r.cell is not None:
            _print_cell(r.cell, sys.stdout)
        if not r.ok:
            print(f"error: {r.error}", file=sys.stderr)
    return 0 if ok else 1


def load_schedulable(name: str) -> Any:
    """A problem from a problem JSON, an FJSP file, a cell file or a built-in cell's name."""
    from scheduler import detect_format, load_problem, read_fjsp
    from workcell.cell import EXAMPLES, load_example

    path = Path(name)
    if not path.exists() and name in EXAMPLES:
        from workcell import compile_cell

        return compile_cell(load_example(name)).problem
    if path.suffix.lower() == ".fjs" or (path.is_file() and detect_format(path) == "fjsp"):
        return read_fjsp(path)
    if path.suffix.lower() == ".toml":
        from workcell import compile_cell, load_cell

        return compile_cell(load_cell(path)).problem
    return load_problem(path)
