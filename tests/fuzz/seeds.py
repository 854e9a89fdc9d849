"""Writes the generated seed files of ``tests/fuzz/corpus/`` (run after a format change).

Usage::

    python -m tests.fuzz.seeds

Problem, schedule and task-set files have no hand-written examples in the
repository; their seeds are written here by the package's own writers, small
on purpose (the fuzzer mutates short inputs faster). Fault, FJSP and other
hand-written seeds in ``corpus/`` are kept as they are.
"""

from __future__ import annotations

import dataclasses
import json
import sys

from tests.fuzz.targets import HERE, schedule_problem

__all__ = ["main"]


def main() -> int:
    """Write the generated seeds; returns 0."""
    from scheduler import TreeOptions, solve
    from scheduler.fjsp import parse_fjsp
    from scheduler.generate import random_problem
    from scheduler.io import save_problem
    from tasklib import generate_taskset, load_example, save_taskset

    corpus = HERE / "corpus"
    for d in ("problem", "schedule", "taskset_toml", "taskset_json"):
        (corpus / d).mkdir(parents=True, exist_ok=True)
    problems = {
        "zones_setups": random_problem(2, 4, 2, 1, seed=0),
        "start_zones": random_problem(3, 5, 1, 0, seed=1, start_zones=True, setups=False),
        "fjsp": parse_fjsp("2 3\n2 1 1 5 2 1 3 2 2\n1 1 2 4\n", name="fjsp"),
    }
    for name, problem in problems.items():
        save_problem(problem, corpus / "problem" / f"{name}.json")
    problem = schedule_problem()
    for solver, options in (("greedy", None), ("tree", TreeOptions(max_evaluations=200))):
        result = solve(problem, solver, time_limit=None, seed=0, options=options)
        text = json.dumps(result.schedule.to_dict(problem), indent=1) + "\n"
        (corpus / "schedule" / f"{solver}.json").write_text(text, encoding="utf-8")
    full = load_example("supersigma")
    tiny = dataclasses.replace(
        full,
        tasks=tuple(t for t in full.tasks if not t.prerequisites and not t.consumes)[:2],
        groups=(),
    )
    for name, ts in {"generated": generate_taskset(3, seed=0), "supersigma2": tiny}.items():
        save_taskset(ts, corpus / "taskset_toml" / f"{name}.toml")
        save_taskset(ts, corpus / "taskset_json" / f"{name}.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
