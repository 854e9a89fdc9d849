"""Running a fault campaign: batches of episodes through the sweep runner.

A campaign is ``episodes`` episodes per cell (:mod:`.episodes`), cut into
batches; each batch is one run of a sweep (a ``benchmark`` run calling
:func:`campaign_batch`, :mod:`workcell.experiments.sweep`), so a campaign
runs in a local process pool or on a Dask cluster, streams to a journal and
resumes where it stopped. :func:`run_campaign` gathers the episodes into one
table (:data:`COLUMNS`) and :class:`CampaignOutcome` summarises it; every
finding comes with the command that replays it (:func:`replay`).

A sweep file runs a campaign with an instance of kind ``campaign``::

    [[instances]]
    kind = "campaign"
    cells = ["supersigma", "scara4"]
    episodes = 300          # per cell and seed
    batch = 25              # episodes per run
    seeds = [0]             # campaign seeds
"""

from __future__ import annotations

import json
import math
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

from multiarm.errors import UsageError
from workcell.campaign.episodes import (
    EpisodeResult,
    draw_episode,
    prepare,
    run_episode,
)
from workcell.cell import EXAMPLES
from workcell.experiments.executors import run_sweep
from workcell.experiments.grid import Sweep
from workcell.experiments.instances import (
    CAMPAIGN_BATCH,
    CAMPAIGN_FUNCTION,
    campaign_instances,
)

__all__ = [
    "BATCH",
    "COLUMNS",
    "FUNCTION",
    "CampaignOutcome",
    "campaign_batch",
    "campaign_instances",
    "describe",
    "parse_replay",
    "replay",
    "run_campaign",
]

FUNCTION = CAMPAIGN_FUNCTION
BATCH = CAMPAIGN_BATCH

COLUMNS: tuple[str, ...] = (
    "cell",
    "seed",
    "episode",
    "medium",
    "coordination",
    "resolve",
    "sim_seed",
    "n_faults",
    "fault_kinds",
    "faults",
    "replayed",
    "outcome",
    "finding_kinds",
    "findings",
    "executed_makespan",
    "done",
    "failed",
    "wall_time",
    "command",
)
"""Columns of the episodes table, in order (:meth:`EpisodeResult.row`)."""


def campaign_batch(
    seed: int,
    cell: str,
    first: int = 0,
    count: int = BATCH,
) -> list[dict[str, Any]]:
    """Episodes ``first`` to ``first + count - 1`` of campaign ``seed`` on ``cell``.

    The sweep runner's measurement function: one row per episode
    (:meth:`EpisodeResult.row`). The cell is compiled and planned once per
    process.

    Parameters
    ----------
    seed : int
        The campaign's seed.
    cell : str
        A built-in cell's name or a cell file.
    first, count : int
        The episodes of this batch.

    Returns
    -------
    list of dict
    """
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise UsageError(f"campaign: count must be an integer >= 1, got {count!r}")
    cc = prepare(cell)
    return [run_episode(cc, draw_episode(cc, seed, i)).row() for i in range(first, first + count)]


@dataclass(frozen=True, slots=True)
class CampaignOutcome:
    """What :func:`run_campaign` did.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per episode (:data:`COLUMNS`), sorted by cell, seed, episode.
    errors : tuple of str
        Batches that could not run at all (a cell that does not compile, a
        worker lost), with their messages.
    wall_time : float
        Seconds of wall clock.
    out : Path or None
        The directory the tables went to.
    """

    table: Any
    errors: tuple[str, ...]
    wall_time: float
    out: Path | None

    @property
    def findings(self) -> int:
        """Episodes with at least one finding."""
        return int((self.table["outcome"] == "finding").sum()) if len(self.table) else 0

    def counts(self, by: str) -> dict[str, int]:
        """Findings (one per episode and kind) counted by ``by``: ``"kind"``,
        ``"medium"``, ``"fault_kind"``, ``"cell"``, ``"resolve"`` or ``"coordination"``.

        Raises
        ------
        UsageError
            An unknown ``by``.
        """
        if by not in ("kind", "medium", "fault_kind", "cell", "resolve", "coordination"):
            raise UsageError(f"CampaignOutcome.counts: unknown grouping {by!r}")
        out: dict[str, int] = {}
        for r in self.table.to_dict("records"):
            kinds = [k for k in str(r["finding_kinds"]).split(",") if k]
            if not kinds:
                continue
            if by == "kind":
                keys = kinds
            elif by == "fault_kind":
                keys = sorted(set(str(r["fault_kinds"]).split(",")))
            else:
                keys = [str(r[by])]
            for k in keys:
                out[k] = out.get(k, 0) + 1
        return dict(sorted(out.items(), key=lambda kv: (-kv[1], kv[0])))

    def summary(self) -> str:
        """One line: episodes, findings by kind, replays, time."""
        t = self.table
        n = len(t)
        kinds = ", ".join(f"{k} {v}" for k, v in self.counts("kind").items())
        cells = ", ".join(dict.fromkeys(map(str, t["cell"]))) if n else "-"
        replayed = int(t["replayed"].sum()) if n else 0
        line = (
            f"campaign {cells}: {n} episodes, {self.findings} with findings"
            + (f" ({kinds})" if kinds else "")
            + f", {replayed} replayed, {self.wall_time:.1f} s"
        )
        if self.errors:
            line += f"; {len(self.errors)} batches failed to run"
        return line

    def report(self, limit: int = 50) -> str:
        """The summary, then each episode with findings: its findings and the
        command that replays it (at most ``limit`` episodes)."""
        lines = [self.summary()]
        bad = self.table[self.table["outcome"] == "finding"]
        for r in bad.head(limit).to_dict("records"):
            kinds = str(r["finding_kinds"])
            lines.append(f"  {r['cell']} episode {r['episode']} ({kinds}): {r['command']}")
            for k, _task, detail in json.loads(str(r["findings"]))[:3]:
                lines.append(f"      {k}: {detail}")
        if len(bad) > limit:
            lines.append(
                f"  ... and {len(bad) - limit} more episodes with findings (see the table)"
            )
        lines += [f"  error: {e}" for e in self.errors]
        return "\n".join(lines)


class _Progress:
    """A progress bar over episodes on a terminal; one line per batch when piped."""

    def __init__(self, total: int, enabled: bool) -> None:
        self.total, self.done, self.bad = total, 0, 0
        self.enabled = enabled
        self.bar: Any = None
        if enabled and sys.stderr.isatty():
            from tqdm import tqdm  # type: ignore[import-untyped,unused-ignore]

            self.bar = tqdm(total=total, desc="campaign", unit="episode", file=sys.stderr)

    def update(self, rows: Sequence[dict[str, Any]]) -> None:
        self.done += len(rows)
        self.bad += sum(r["outcome"] == "finding" for r in rows)
        if self.bar is not None:
            self.bar.update(len(rows))
            self.bar.set_postfix(findings=self.bad)
        elif self.enabled:
            print(
                f"campaign: {self.done}/{self.total} episodes, {self.bad} with findings",
                file=sys.stderr,
                flush=True,
            )

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def run_campaign(
    cells: Sequence[str],
    episodes: int,
    seed: int = 0,
    *,
    workers: int | None = None,
    dask_address: Any = None,
    out: str | PathLike[str] | None = None,
    batch: int | None = None,
    progress: bool = False,
    on_rows: Callable[[list[dict[str, Any]]], None] | None = None,
) -> CampaignOutcome:
    """Run ``episodes`` episodes per cell of campaign ``seed`` and check each.

    Parameters
    ----------
    cells : sequence of str
        Built-in cells' names or cell files.
    episodes : int
        Per cell.
    seed : int
        The campaign's seed: the same seed gives the same episodes and findings.
    workers : int, optional
        Local processes (default: the CPU count; 1 runs in this process).
    dask_address : str or distributed.Client, optional
        Run on this Dask cluster instead.
    out : str or path-like, optional
        A directory: the sweep's journal (``runs.parquet``, so a campaign
        interrupted resumes) and the episodes table (``episodes.parquet``,
        ``episodes.csv``). Default: a temporary directory, nothing kept.
    batch : int, optional
        Episodes per sweep run (default: an eighth of ``episodes``, between
        5 and :data:`BATCH`, so that every worker has several).
    progress : bool
        A progress bar on a terminal, one line per batch on stderr otherwise.
    on_rows : callable, optional
        Called with each batch's episode rows as they arrive.

    Returns
    -------
    CampaignOutcome

    Raises
    ------
    UsageError
        Bad counts, an unknown cell (found when the batches start), an
        unreachable scheduler.
    """
    import pandas as pd

    t0 = time.perf_counter()
    if batch is None:
        batch = max(5, min(BATCH, math.ceil(episodes / 8))) if isinstance(episodes, int) else 1
    instances = campaign_instances(cells, episodes, (seed,), batch)
    for c in cells:
        _check_cell(c)  # before any process starts
    tmp = None
    if out is None:
        tmp = tempfile.TemporaryDirectory(prefix="multiarm-campaign-")
        directory = Path(tmp.name)
    else:
        directory = Path(out)
        directory.mkdir(parents=True, exist_ok=True)
    sweep = Sweep(
        name="campaign",
        description=f"fault campaign, seed {seed}",
        out=directory / "runs.parquet",
        repetitions=1,
        instances=tuple(instances),
        solvers=(),
    )
    bar = _Progress(episodes * len(cells), progress)

    def row_arrived(row: dict[str, Any]) -> None:
        if row["status"] != "measured":
            return
        rows = json.loads(row["metrics"])
        bar.update(rows)
        if on_rows is not None:
            on_rows(rows)

    try:
        done = run_sweep(
            sweep, dask_address=dask_address, workers=workers, progress=False, on_row=row_arrived
        )
        results = done.results(current=True)
    finally:
        bar.close()
    rows: list[dict[str, Any]] = []
    errors: list[str] = []
    for r in results.to_dict("records"):
        if r["status"] == "measured":
            rows += json.loads(r["metrics"])
        else:
            errors.append(f"{r['instance']}: {r.get('error_type', '')}: {r.get('error', '')}")
    table = pd.DataFrame(rows, columns=list(COLUMNS))
    if len(table):
        order = {c: i for i, c in enumerate(cells)}
        table["_order"] = table["cell"].map(order)
        table = table.sort_values(["_order", "seed", "episode"]).drop(columns="_order")
        table = table.reset_index(drop=True)
    if out is not None:
        table.to_parquet(directory / "episodes.parquet", index=False)
        table.to_csv(directory / "episodes.csv", index=False)
    if tmp is not None:
        tmp.cleanup()
    return CampaignOutcome(
        table, tuple(errors), time.perf_counter() - t0, None if out is None else directory
    )


def _check_cell(cell: str) -> None:
    p = Path(cell)
    if cell not in EXAMPLES and not (p.is_file() and p.suffix.lower() == ".toml"):
        raise UsageError(
            f"campaign: unknown cell {cell!r}: not a built-in cell ({', '.join(EXAMPLES)}) "
            "nor a .toml cell file"
        )


def parse_replay(text: str) -> tuple[int, int]:
    """``"SEED:EPISODE"`` as two integers.

    Raises
    ------
    UsageError
        Anything else.

    Examples
    --------
    >>> parse_replay("0:17")
    (0, 17)
    """
    seed, sep, index = str(text).partition(":")
    if not sep or not seed.isdigit() or not index.isdigit():
        raise UsageError(f"--replay: expected SEED:EPISODE (two integers >= 0), got {text!r}")
    return int(seed), int(index)


def replay(cell: str, seed: int, index: int) -> EpisodeResult:
    """Draw, run and check episode ``index`` of campaign ``seed`` on ``cell`` again.

    Returns
    -------
    EpisodeResult
        With the same findings as in the campaign (the run is deterministic).
    """
    _check_cell(cell)
    cc = prepare(cell)
    return run_episode(cc, draw_episode(cc, seed, index))


def describe(result: EpisodeResult) -> str:
    """An episode and its findings as text (what ``--replay`` prints)."""
    e = result.episode
    lines = [
        f"{e.cell} episode {e.index} of campaign seed {e.seed}: medium {e.medium!r}, "
        f"coordination {e.coordination!r}, re-solving {'on' if e.resolve else 'off'}, "
        f"simulation seed {e.sim_seed}",
        f"faults: {e.faults_json()}",
        f"executed makespan {result.executed_makespan:.6g} s, {result.done} tasks done, "
        f"{result.failed} failed"
        if math.isfinite(result.executed_makespan)
        else "no task done",
    ]
    if result.findings:
        lines.append(f"{len(result.findings)} findings:")
        lines += [f"  {f.kind}: {f.detail}" for f in result.findings]
    else:
        lines.append("no findings")
    return "\n".join(lines)
