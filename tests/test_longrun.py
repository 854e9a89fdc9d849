"""benchmarks/bench_longrun.py: the split of a cell's gap into the plan's share and the rest."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd
import pytest

from benchmarks.bench_longrun import best_at, reference_of, render, summarise


def _rows(cell: str, runs: dict[float, float], curve: list[list[float]]) -> list[dict[str, object]]:
    return [
        {
            "instance": cell,
            "time_limit": t,
            "makespan": mk,
            "lower_bound": 80.0,
            "n_tasks": 20,
            "improvements": json.dumps(curve if t == max(runs) else [[0.5, mk]]),
        }
        for t, mk in runs.items()
    ]


def test_summarise_splits_the_gap() -> None:
    """The 10 s plan of 130 against a bound of 100 and a best known of 120 (a
    longer run): a third of its gap is the plan's."""
    df = pd.DataFrame(
        _rows(
            "c",
            {10.0: 130.0, 60.0: 125.0, 300.0: 120.0},
            [[0.5, 140.0], [4.0, 131.0], [200.0, 121.0], [300.02, 120.0]],
        )
    )
    ref = {"c": {"best bound (s)": 100.0, "exact (s)": "-", "proven?": "no"}}
    (c,) = summarise(df, ref)
    assert c["bound"] == 100.0 and c["bound_source"] == "cells.md best bound"
    assert c["best_known"] == 120.0 and c["best_from"] == "these runs"
    assert c["share_of_gap_closed"] == pytest.approx(1 / 3)
    assert c["shortest_above_best"] == pytest.approx(10 / 120)
    assert c["curve"][1.0] == 140.0 and c["curve"][5.0] == 131.0 and c["curve"][120.0] == 131.0
    assert c["curve"][300.0] == 120.0  # found as the run ended, just past its limit
    text = render([c], "longrun.png")
    assert "| c | 20 | 100.00 | cells.md best bound | no | 130.00 | 30.0% |" in text
    assert "| 120.00 | these runs | 8.3% | 33.3% |" in text


def test_summarise_takes_the_exact_schedule_and_the_proven_optimum() -> None:
    """A shorter schedule from the exact search is the best known; a proven
    cell's bound is the optimum itself (the table rounds its bound); without a
    reference row the runner's lower bound is used."""
    df = pd.DataFrame(
        _rows("p", {10.0: 131.0}, [[1.0, 131.0]]) + _rows("q", {10.0: 90.0}, [[1.0, 90.0]])
    )
    ref = {"p": {"best bound (s)": 128.41, "exact (s)": 128.413, "proven?": "yes"}}
    p, q = summarise(df, ref)
    assert p["bound"] == 128.413 and p["proven"]
    assert p["best_known"] == 128.413 and p["best_from"] == "exact search (cells.md)"
    assert p["share_of_gap_closed"] == pytest.approx(1.0)
    assert q["bound"] == 80.0 and q["bound_source"] == "lower_bound"
    assert q["share_of_gap_closed"] == 0.0
    assert math.isnan(
        summarise(pd.DataFrame(_rows("r", {10.0: 80.0}, [])), {})[0]["share_of_gap_closed"]
    )


def test_best_at_and_missing_reference(tmp_path: Path) -> None:
    assert best_at([[2.0, 5.0], [1.0, 6.0]], 1.0) == 6.0
    assert best_at([], 10.0) is None
    assert reference_of(tmp_path / "cells.json") == {}
    (tmp_path / "cells.json").write_text(json.dumps({"reference": [{"cell": "x", "tasks": 1}]}))
    assert reference_of(tmp_path / "cells.json") == {"x": {"cell": "x", "tasks": 1}}
