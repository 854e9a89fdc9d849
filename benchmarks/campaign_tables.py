"""Gather fault-campaign episode tables into ``benchmarks/results/campaign.*``.

``python -m benchmarks.campaign_tables DIR [DIR ...] [--commit SHA] [--note TEXT]``
reads ``DIR/episodes.parquet`` of each ``multiarm campaign ... --out DIR``
run, writes them as one table to ``benchmarks/results/campaign.parquet`` and
its summary (totals, then episodes and findings by cell, coordination
policy, medium, fault kind and re-solving, then every finding with the
command that replays it) to ``benchmarks/results/campaign.md``. The campaign
itself is the ``multiarm campaign`` commands the summary lists; this script
only counts.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

RESULTS = Path(__file__).resolve().parent / "results"


def _share(bad: int, n: int) -> str:
    return f"{100.0 * bad / n:.1f} %" if n else "-"


def _group(table: Any, title: str, keys: Sequence[tuple[str, Any]]) -> list[str]:
    """A table of episodes, episodes with findings and their share per key."""
    lines = [f"| {title} | episodes | with findings | share |", "|---|---|---|---|"]
    for label, mask in keys:
        sub = table[mask]
        bad = int((sub["outcome"] == "finding").sum())
        lines.append(f"| {label} | {len(sub)} | {bad} | {_share(bad, len(sub))} |")
    return lines


def summary(table: Any, commands: Sequence[str], commit: str, note: str = "") -> str:
    """The markdown text of ``campaign.md`` for ``table`` (the episodes table)."""
    n = len(table)
    bad = table[table["outcome"] == "finding"]
    cells = list(dict.fromkeys(map(str, table["cell"])))
    per_cell = ", ".join(f"{int((table['cell'] == c).sum())} on `{c}`" for c in cells)
    seeds = sorted({int(s) for s in table["seed"]})
    kinds: dict[str, int] = {}
    for r in bad.to_dict("records"):
        for k in str(r["finding_kinds"]).split(","):
            kinds[k] = kinds.get(k, 0) + 1
    kind_text = ", ".join(f"{k} {v}" for k, v in sorted(kinds.items(), key=lambda kv: -kv[1]))
    replayed = int(table["replayed"].sum())
    replay_bad = int(table["finding_kinds"].astype(str).str.contains("replay").sum())
    cpu = float(table["wall_time"].sum())
    lines = [
        "# Fault campaign",
        "",
        f"{n} episodes, campaign seed {', '.join(map(str, seeds))}: {per_cell}; "
        + (
            f"**{len(bad)} episodes with findings** ({_share(len(bad), n)}: {kind_text})"
            if len(bad)
            else "**no finding**"
        )
        + f"; {replayed} episodes replayed, {replay_bad} differed.",
        "",
        "Each episode: 1-4 faults over every fault kind, times uniform over the plan or "
        "on (or 1e-9 s / 1e-6 s off) planned task starts and ends, every medium, both "
        "coordination policies, re-solving on and off; checked for an exception, a "
        "safety-monitor violation, an unexplained failed task, a failed task a surviving "
        "arm can do, releases and precedences, and (5 %) an exact replay "
        '(docs/simulation.md, "Fault campaigns"). Distributed episodes are judged as with '
        "re-solving off, since that policy keeps the plan. An episode counts once per "
        "group it falls in.",
        "",
    ]
    lines += _group(table, "cell", [(c, table["cell"] == c) for c in cells])
    lines.append("")
    pol = sorted(set(map(str, table["coordination"])))
    lines += _group(table, "coordination", [(p, table["coordination"] == p) for p in pol])
    lines.append("")
    media = sorted(set(map(str, table["medium"])))
    lines += _group(table, "medium", [(m, table["medium"] == m) for m in media])
    lines.append("")
    fk = table["fault_kinds"].astype(str).str.split(",")
    every = sorted({k for ks in fk for k in ks})
    lines += _group(
        table, "fault kind in the plan", [(k, fk.map(lambda ks, k=k: k in ks)) for k in every]
    )
    lines.append("")
    nf = sorted({int(x) for x in table["n_faults"]})
    lines += _group(table, "faults in the plan", [(str(k), table["n_faults"] == k) for k in nf])
    lines.append("")
    rows = []
    for p in pol:
        for r in (True, False):
            label = f"{p}, re-solving {'on' if r else 'off'}"
            rows.append((label, (table["coordination"] == p) & (table["resolve"] == r)))
    lines += _group(table, "policy and re-solving", rows)
    lines.append("")
    failed = int((table["failed"] > 0).sum())
    lines.append(
        f"{failed} episodes failed some task, every failure explained by the episode's "
        "faults (the checks above); the tasks frame of each is in the table."
        if not len(bad)
        else f"{failed} episodes failed some task."
    )
    lines.append("")
    if len(bad):
        lines.append("Findings (each replays with its command):")
        lines.append("")
        for r in bad.to_dict("records"):
            lines.append(
                f"* `{r['command']}` ({r['finding_kinds']}; {r['coordination']}, "
                f"{r['medium']}, re-solving {'on' if r['resolve'] else 'off'})"
            )
            for k, _task, detail in json.loads(str(r["findings"]))[:3]:
                lines.append(f"  * {k}: {detail}")
        lines.append("")
    if note:
        lines += [note, ""]
    lines += [
        "Reproduce (each `--out DIR` holds that cell's `episodes.parquet`; the runs took "
        f"{cpu / 3600:.2f} h of episode wall time in all, on 2 shared cores):",
        "",
        "```sh",
        *commands,
        "```",
        "",
        "Table: `campaign.parquet` (one row per episode; `python -m "
        f"benchmarks.campaign_tables DIR ...` writes it and this page). Code: commit {commit}.",
        "",
    ]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    import pandas as pd

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="+", help="--out directories of multiarm campaign runs")
    ap.add_argument("--commit", default="(not given)")
    ap.add_argument("--command", action="append", default=[], help="a command that ran")
    ap.add_argument("--note", default="")
    a = ap.parse_args(argv)
    table = pd.concat(
        [pd.read_parquet(Path(d) / "episodes.parquet") for d in a.dirs], ignore_index=True
    )
    table.to_parquet(RESULTS / "campaign.parquet", index=False)
    text = summary(table, a.command, a.commit, a.note)
    (RESULTS / "campaign.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
