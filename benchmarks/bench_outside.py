"""Zone problems from two families the solvers were not developed on: tree against CP-SAT.

A thin wrapper of the sweep ``benchmarks/sweeps/outside.toml``: problems
from :mod:`scheduler.families` (``routes``: a flexible job shop whose
operations enter zones for part of their time; ``stations``: assembly kits
at exclusive stations behind shared corridors, with travel setups), 2-6
arms, 20-100 tasks, 2-6 zones, 0-2 tools, waits on and off, each solved by
``tree`` and ``cpsat`` at the same wall budget on the same 2 cores. Per
problem the table gives both makespans and statuses, the time each found
its final schedule and, when it proved it optimal, the time of the proof
(its runtime, as it stops there); per family how often the tree is behind
CP-SAT, and the tree's mean gap to CP-SAT's proven optima. It runs the
sweep (resuming; ``--fresh`` to start over) into
``benchmarks/results/outside.parquet`` and writes :func:`outside_table` to
``outside.md`` and ``outside.json``. ``--tune`` runs the tuning sweep
``benchmarks/sweeps/outside_tune.toml`` instead (the ``routes`` problems,
the tree with and without the race beside CP-SAT) and writes
:func:`tune_table` to ``outside_tune.md``. ``--seeds`` runs
``benchmarks/sweeps/outside_seeds.toml`` (the table's ``routes`` problems,
both solvers with solver seeds 0-2) and writes :func:`seed_table` to
``outside_seeds.md``: whether a difference of one run is more than the
run-to-run spread.

Run: ``python -m benchmarks.bench_outside [--fresh] [--workers N] [--quick] [--tune | --seeds]``.
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

from benchmarks.common import output_dir, publish, run_table_sweep, sweep_arguments, write

NAME = "outside"


def _fmt(x: float) -> str:
    return f"{x:g}" if math.isfinite(x) else "none"


def _fmt_mean(x: float) -> str:
    return f"{x:.1f}" if math.isfinite(x) else "none"


def _or_inf(x: float) -> float:
    """A makespan, or infinity for a run without a schedule (nan)."""
    return x if math.isfinite(x) else math.inf


def outside_table(df: Any, *, sweep: str = NAME, tree: str = "tree", cpsat: str = "cpsat") -> str:
    """The Markdown table of ``benchmarks/results/outside.md`` from the sweep's results.

    Parameters
    ----------
    df : pandas.DataFrame
        Results of ``sweeps/<sweep>.toml`` (one run per instance and label).
    sweep : str
        The sweep file's stem (named in the heading).
    tree, cpsat : str
        The two solver labels compared.

    Returns
    -------
    str
        Markdown: per family a table of both solvers' makespans, statuses,
        time of their final schedule and of their proof, and the summary
        lines (behind / ahead / equal, proven optima reached, mean gap).
    """
    a = df[df["label"] == tree].set_index(["family", "instance"])
    b = df[df["label"] == cpsat].set_index(["family", "instance"])
    limit = float(df["time_limit"].max())
    lines = [
        f"# Zone problems from other generators: {tree} vs {cpsat}",
        "",
        f"{limit:g} s per solver and problem, both on the machine's 2 cores (sweep "
        f"`benchmarks/sweeps/{sweep}.toml`); size = arms x tasks x zones x tools, '-nowait': "
        "solved with `waits=False`. 'found': seconds to the final schedule; 'proof': seconds "
        "to the proof of optimality (the run ends there; '-': none within the limit).",
    ]
    total_behind = total = 0
    for family in sorted({k[0] for k in a.index}):
        keys = sorted(
            (k for k in a.index if k[0] == family and k in b.index),
            key=lambda k: (json.loads(str(a.loc[k]["instance_params"]))["tasks"], k[1]),
        )
        lines += [
            "",
            f"## {family}",
            "",
            f"| problem | {tree} | status | found | proof | {cpsat} | status | found | proof | "
            "difference |",
            "|---|---|---|---|---|---|---|---|---|---|",
        ]
        behind = ahead = 0
        closed: list[tuple[float, float, float, float]] = []  # (tree mk, optimum, proofs)
        for k in keys:
            ra, rb = a.loc[k], b.loc[k]
            ma, mb = float(ra["makespan"]), float(rb["makespan"])
            cells = []
            for r in (ra, rb):
                found = float(r["best_time"]) if math.isfinite(float(r["makespan"])) else math.nan
                proof = f"{float(r['runtime']):.2f}" if r["status"] == "optimal" else "-"
                cells.append(
                    f"{_fmt(float(r['makespan']))} | {r['status']} | {found:.2f} | {proof}"
                    if math.isfinite(found)
                    else f"none | {r['status']} | - | -"
                )
            if ma > mb + 1e-9:
                behind += 1
            elif ma < mb - 1e-9:
                ahead += 1
            diff = (
                (ma - mb) / mb if math.isfinite(ma) and math.isfinite(mb) and mb > 0 else math.nan
            )
            dtxt = f"{100 * diff:+.2f}%" if math.isfinite(diff) else "-"
            lines.append(f"| {k[1]} | " + " | ".join(cells) + f" | {dtxt} |")
            if rb["status"] == "optimal":
                proof_a = float(ra["runtime"]) if ra["status"] == "optimal" else math.nan
                closed.append((ma, mb, proof_a, float(rb["runtime"])))
        n = len(keys)
        total += n
        total_behind += behind
        lines += [
            "",
            f"- {tree} behind {cpsat} at the same {limit:g} s on {behind} of {n}, ahead on "
            f"{ahead}, equal on {n - behind - ahead}",
        ]
        if closed:
            hit = sum(ma <= opt + 1e-9 for ma, opt, _, _ in closed)
            proved = [pa for _, _, pa, _ in closed if math.isfinite(pa)]
            gap = sum((ma - opt) / opt for ma, opt, _, _ in closed) / len(closed)
            cp_mean = sum(pb for _, _, _, pb in closed) / len(closed)
            lines.append(
                f"- {cpsat} proved {len(closed)} of {n} optimal (mean time to the proof "
                f"{cp_mean:.2f} s); on those {tree} returns the optimum on {hit}, proves it on "
                f"{len(proved)}"
                + (f" (mean {sum(proved) / len(proved):.2f} s)" if proved else "")
                + f", mean gap {100 * gap:.2f}%"
            )
    lines += ["", f"All: {tree} behind {cpsat} on {total_behind} of {total}."]
    return "\n".join(lines) + "\n"


def seed_table(df: Any, *, tree: str = "tree", cpsat: str = "cpsat") -> str:
    """The table of ``benchmarks/results/outside_seeds.md`` (``sweeps/outside_seeds.toml``).

    Parameters
    ----------
    df : pandas.DataFrame
        Results with one run per (instance, solver label, seed).
    tree, cpsat : str
        The two solver labels compared.

    Returns
    -------
    str
        Markdown: per problem each seed's makespan of both solvers, their means
        and ranges and the difference of the means; then how often the tree is
        behind with each seed, behind on the mean, and behind beyond the spread
        (its best seed longer than CP-SAT's worst).

    Examples
    --------
    >>> import pandas as pd
    >>> rows = [("p", "tree", 0, 10.0), ("p", "tree", 1, 12.0), ("p", "cpsat", 0, 11.0),
    ...         ("p", "cpsat", 1, 11.0), ("q", "tree", 0, 9.0), ("q", "tree", 1, 9.0),
    ...         ("q", "cpsat", 0, 8.0), ("q", "cpsat", 1, 8.0)]
    >>> df = pd.DataFrame(rows, columns=["instance", "label", "seed", "makespan"])
    >>> df = df.assign(family="routes", time_limit=1.0,
    ...                instance_params='{"tasks": 5}')
    >>> print(seed_table(df).splitlines()[-1])
    - behind on the mean: 1 of 2 (by 12.50% at most); beyond the spread (the tree's best seed longer than cpsat's worst): 1 of 2
    """
    limit = float(df["time_limit"].max())
    seeds = sorted({int(v) for v in df["seed"].dropna()})
    stxt = (
        f"{seeds[0]}-{seeds[-1]}"
        if seeds == list(range(seeds[0], seeds[-1] + 1))
        else (", ".join(map(str, seeds)))
    )
    mk: dict[tuple[str, str, int], float] = {}
    tasks: dict[str, int] = {}
    for r in df.itertuples(index=False):
        mk[(str(r.label), str(r.instance), int(r.seed))] = float(r.makespan)
        tasks[str(r.instance)] = int(json.loads(str(r.instance_params))["tasks"])
    keys = sorted(tasks, key=lambda k: (tasks[k], k))
    family = ", ".join(sorted({str(f) for f in df["family"]}))
    lines = [
        f"# The outside table's {family} problems over solver seeds: {tree} vs {cpsat}",
        "",
        f"{limit:g} s per solver, problem and seed, both on the machine's 2 cores (sweep "
        "`benchmarks/sweeps/outside_seeds.toml`); solver seeds "
        f"{stxt}. The outside table runs each solver once per problem (its seed the "
        "problem's); here each runs once per seed, so a difference can be told from the "
        "run-to-run spread. Makespans validated; '-nowait': solved with `waits=False`.",
        "",
        f"| problem | {tree}: seeds {stxt} | {tree} mean (min-max) | {cpsat}: seeds {stxt} "
        f"| {cpsat} mean (min-max) | mean difference |",
        "|---|---|---|---|---|---|",
    ]
    per_seed = dict.fromkeys(seeds, 0)
    behind_mean = beyond = 0
    worst = 0.0
    missing = {tree: 0, cpsat: 0}
    for k in keys:
        # a run without a schedule (or not run) counts as longer than any schedule
        got = {x: [_or_inf(mk.get((x, k, s), math.nan)) for s in seeds] for x in (tree, cpsat)}
        for x in (tree, cpsat):
            missing[x] += sum(math.isinf(v) for v in got[x])
        for s, a, b in zip(seeds, got[tree], got[cpsat], strict=True):
            per_seed[s] += a > b + 1e-9
        ma = sum(got[tree]) / len(seeds)
        mb = sum(got[cpsat]) / len(seeds)
        diff = (ma - mb) / mb if math.isfinite(ma) and math.isfinite(mb) and mb > 0 else math.nan
        if ma > mb + 1e-9:
            behind_mean += 1
            worst = max(worst, diff) if math.isfinite(diff) else worst
        if min(got[tree]) > max(got[cpsat]) + 1e-9:
            beyond += 1
        cells = [
            " ".join(_fmt(v) for v in got[x])
            + f" | {_fmt_mean(sum(got[x]) / len(seeds))} ({_fmt(min(got[x]))}-{_fmt(max(got[x]))})"
            for x in (tree, cpsat)
        ]
        dtxt = f"{100 * diff:+.2f}%" if math.isfinite(diff) else "-"
        lines.append(f"| {k} | " + " | ".join(cells) + f" | {dtxt} |")
    n = len(keys)
    lines += [
        "",
        f"- {tree} behind {cpsat} with the same seed: "
        + ", ".join(f"seed {s} on {per_seed[s]} of {n}" for s in seeds),
        f"- behind on the mean: {behind_mean} of {n}"
        + (f" (by {100 * worst:.2f}% at most)" if behind_mean else "")
        + f"; beyond the spread (the {tree}'s best seed longer than {cpsat}'s worst): {beyond} of {n}",
    ]
    if any(missing.values()):
        lines.append(
            "- runs without a schedule ('none', counted as longer than any schedule; a "
            "mean over them is 'none'): "
            + ", ".join(f"{x} {missing[x]} of {n * len(seeds)}" for x in (tree, cpsat))
        )
    lines.append("")
    return "\n".join(lines)


def tune_table(df: Any, *, limit: int = 40) -> str:
    """The table of ``benchmarks/results/outside_tune.md`` (``sweeps/outside_tune.toml``).

    Parameters
    ----------
    df : pandas.DataFrame
        Results with the labels ``tree_race16``, ``tree_race100`` and ``cpsat``.
    limit : int
        The size rule chosen from it (problems up to ``limit`` tasks race).

    Returns
    -------
    str
        Markdown: per problem the three makespans and statuses; per size band
        how often racing CP-SAT beat a second tree process, and how often
        each was behind CP-SAT.
    """
    labels = ("tree_race16", "tree_race100", "cpsat")
    t = {x: df[df["label"] == x].set_index("instance") for x in labels}
    keys = sorted(
        t["cpsat"].index,
        key=lambda k: (json.loads(str(t["cpsat"].loc[k]["instance_params"]))["tasks"], k),
    )
    tl = float(df["time_limit"].max())
    lines = [
        "# Tuning the race rule on the routes family",
        "",
        f"{tl:g} s per run on the machine's 2 cores (sweep `benchmarks/sweeps/outside_tune.toml`). "
        "`tree_race16`: the tree's earlier rule (a second tree process above 16 tasks); "
        "`tree_race100`: the tree racing CP-SAT (one worker) on every problem of the family; "
        "`cpsat`: CP-SAT alone on 2 workers. '(optimal)': the run proved its schedule optimal.",
        "",
        "| problem | tasks | tree_race16 | tree_race100 | cpsat | race - fork |",
        "|---|---|---|---|---|---|",
    ]
    bands: dict[bool, list[tuple[float, float, float, bool, bool]]] = {True: [], False: []}
    for k in keys:
        tasks = int(json.loads(str(t["cpsat"].loc[k]["instance_params"]))["tasks"])
        mk = [float(t[x].loc[k]["makespan"]) for x in labels]
        opt = [t[x].loc[k]["status"] == "optimal" for x in labels]
        cells = [_fmt(m) + (" (optimal)" if o else "") for m, o in zip(mk, opt, strict=True)]
        lines.append(f"| {k} | {tasks} | " + " | ".join(cells) + f" | {mk[1] - mk[0]:+g} |")
        bands[tasks <= limit].append((mk[0], mk[1], mk[2], opt[0], opt[1]))
    lines.append("")
    for small, rows in ((True, bands[True]), (False, bands[False])):
        if not rows:
            continue
        ahead = sum(b < a - 1e-9 for a, b, _, _, _ in rows)
        behind = sum(b > a + 1e-9 for a, b, _, _, _ in rows)
        lines.append(
            f"- {'up to' if small else 'above'} {limit} tasks ({len(rows)} problems): racing "
            f"CP-SAT ahead of a second tree process on {ahead}, behind on {behind}; behind "
            f"CP-SAT alone: tree_race16 {sum(a > c + 1e-9 for a, _, c, _, _ in rows)}, "
            f"tree_race100 {sum(b > c + 1e-9 for _, b, c, _, _ in rows)}; proven optimal: "
            f"tree_race16 {sum(o for *_, o, _ in rows)}, tree_race100 {sum(o for *_, o in rows)}"
        )
    lines.append(f"- chosen: `TreeOptions.portfolio_max_tasks = {limit}`")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sweep_arguments(ap)
    which = ap.add_mutually_exclusive_group()
    which.add_argument(
        "--tune",
        action="store_true",
        help="run the tuning sweep outside_tune.toml instead (writes outside_tune.md)",
    )
    which.add_argument(
        "--seeds",
        action="store_true",
        help="run outside_seeds.toml instead: the routes problems with solver seeds 0-2"
        " (writes outside_seeds.md)",
    )
    args = ap.parse_args(argv)
    out = output_dir(args.quick)
    if args.seeds:
        df = run_table_sweep("outside_seeds", args, out)
        path = publish(
            "outside_seeds",
            df,
            seed_table(df),
            out,
            quick=args.quick,
            flags="--seeds --fresh",
            script="bench_outside",
        )
        print(path.read_text())
        return
    if args.tune:
        from workcell.experiments.analysis import sweep_note

        df = run_table_sweep("outside_tune", args, out)
        command = "python -m benchmarks.bench_outside --tune " + (
            "--quick" if args.quick else "--fresh"
        )
        note = sweep_note(df, sweep_file=["benchmarks/sweeps/outside_tune.toml"], command=command)
        rows = json.loads(
            df.drop(columns=["dependencies"], errors="ignore").to_json(orient="records")
        )
        path = write(
            "outside_tune",
            {"command": command, "sweeps": ["outside_tune.toml"], "seeds": [], "rows": rows},
            tune_table(df).rstrip("\n") + "\n\n" + note,
            out,
        )
        print(path.read_text())
        return
    df = run_table_sweep(NAME, args, out)
    path = publish(NAME, df, outside_table(df), out, quick=args.quick, flags="--fresh")
    print(path.read_text())


if __name__ == "__main__":
    main()
