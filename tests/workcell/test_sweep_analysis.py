"""Analysis of sweep results: the numbers behind each plot, the plots, the tables."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from multiarm.errors import UsageError
from workcell.experiments import analysis as A


def rows() -> pd.DataFrame:
    """Two instances, two solvers; instance b has a best-known value, a has not."""
    data = [
        # family, instance, label, makespan, runtime, improvements, best_known, n_tasks
        ("f", "a", "x", 10.0, 2.0, [[0.1, 14.0], [1.0, 10.0]], math.nan, 10),
        ("f", "a", "y", 12.0, 1.0, [[0.5, 12.0]], math.nan, 10),
        ("f", "b", "x", 9.0, 2.0, [[0.2, 9.0]], 8.0, 20),
        ("f", "b", "y", math.inf, 3.0, [], 8.0, 20),
    ]
    return pd.DataFrame(
        [
            {
                "family": f,
                "instance": i,
                "label": label,
                "makespan": m,
                "runtime": r,
                "improvements": json.dumps(imp),
                "best_known": bk,
                "n_tasks": n,
                "bound": 7.0,
            }
            for f, i, label, m, r, imp, bk, n in data
        ]
    )


def test_references_and_gaps() -> None:
    df = A.with_gaps(rows())
    # a: no best-known value, so the best makespan found (10); b: its best-known 8
    assert df["reference"].tolist() == [10.0, 10.0, 8.0, 8.0]
    assert df["gap"].tolist()[:3] == pytest.approx([0.0, 0.2, 0.125])
    assert df["gap"].iloc[3] == math.inf
    assert A.reference(rows(), "bound").tolist() == [7.0] * 4
    with pytest.raises(UsageError, match="how must be"):
        A.reference(rows(), "mean")
    with pytest.raises(UsageError, match=r"needs the columns \['makespan'\]"):
        A.reference(rows().drop(columns="makespan"))


def test_performance_profile_counts_instances_within_tau_of_the_best() -> None:
    prof = A.performance_profile_data(rows(), taus=[1.0, 1.2, 100.0])
    assert prof["x"].tolist() == [1.0, 1.0, 1.0]  # best on both
    assert prof["y"].tolist() == [0.0, 0.5, 0.5]  # 12/10 on a, no schedule on b


def test_incumbents_gap_over_time_and_time_to_target() -> None:
    r = rows().iloc[0]
    assert A.incumbent_at(r, [0.0, 0.1, 0.5, 1.0, 5.0]).tolist() == [
        math.inf,
        14.0,
        14.0,
        10.0,
        10.0,
    ]
    gaps = A.gap_over_time_data(rows(), [0.05, 0.3, 1.5])
    # x: a 14/10 then 10/10, b 9/8 from 0.2 s; median of the two runs
    assert gaps["x"].tolist() == pytest.approx([math.inf, (0.4 + 0.125) / 2, 0.0625])
    ttt = A.time_to_target_data(rows(), target=0.15)
    assert ttt["time"].tolist() == [1.0, math.inf, 0.2, math.inf]


def test_scaling_data_is_median_and_quartiles_per_size() -> None:
    s = A.scaling_data(rows(), "n_tasks", "runtime")
    x = s[s["label"] == "x"]
    assert x["n_tasks"].tolist() == [10, 20] and x["median"].tolist() == [2.0, 2.0]
    gap = A.scaling_data(rows(), "n_tasks", "gap")
    assert gap[gap["label"] == "y"]["runs"].tolist() == [
        1
    ]  # the run without a schedule is left out


def test_every_plot_is_a_figure_that_renders(tmp_path: object) -> None:
    df = rows()
    figs = [
        A.performance_profile(df),
        A.gap_over_time(df),
        A.time_to_target(df),
        A.scaling(df),
        A.box_per_solver(df),
    ]
    for fig in figs:
        assert isinstance(fig, Figure) and len(fig.axes) == 1
        fig.canvas.draw()  # Agg
    assert [t.get_text() for t in figs[-1].axes[0].get_xticklabels()] == ["x", "y\n(1 none)"]


def test_generated_table_targets_optimum_or_bound() -> None:
    base = {
        "family": "g",
        "instance_params": json.dumps({"arms": 2, "tasks": 8, "zones": 2, "tools": 1}),
    }
    df = pd.DataFrame(
        [
            {
                **base,
                "instance": "s0",
                "instance_seed": 0,
                "label": lab,
                "makespan": mk,
                "bound": b,
                "status": st,
                "time_limit": tl,
            }
            for lab, mk, b, st, tl in [
                ("reference", 40.0, 40.0, "optimal", 60.0),
                ("tree", 40.0, 30.0, "feasible", 10.0),
                ("cpsat_short", 42.0, 35.0, "feasible", 10.0),
                ("greedy", 50.0, 30.0, "feasible", 10.0),
            ]
        ]
        + [
            {
                **base,
                "instance": "s1",
                "instance_seed": 1,
                "label": lab,
                "makespan": mk,
                "bound": b,
                "status": st,
                "time_limit": tl,
            }
            for lab, mk, b, st, tl in [
                ("reference", 50.0, 40.0, "feasible", 60.0),
                ("tree", 45.0, 30.0, "feasible", 10.0),
                ("cpsat_short", math.inf, 35.0, "unknown", 10.0),
                ("greedy", 60.0, 30.0, "feasible", 10.0),
            ]
        ]
    )
    table = A.generated_table(df)
    assert "| 2x8x2x1 | 0 | yes | 40.0 | 40 | 40 | 42 | 50 | 0.00% | 5.00% | +0.00% |" in table
    assert "| 2x8x2x1 | 1 | no | 40.0 | 50 | 45 | none | 60 | 12.50% | - | -10.00% |" in table
    assert "on the 1 problems CP-SAT solved to optimality: mean gap of tree 0.00%" in table
    assert "tree -10.00% against it on average" in table
    assert np.isfinite(df["makespan"]).sum() == 7


def test_seed_spread_table_reports_every_seed_and_the_spread_of_the_mean_gap() -> None:
    # tree: seed 0 at the best known on both, seed 1 10 % over on m1; cpsat 20 % over on m2
    data = [
        ("m1", "tree", 0, 10.0), ("m1", "tree", 1, 11.0), ("m2", "tree", 0, 20.0),
        ("m2", "tree", 1, 20.0), ("m1", "cpsat", 0, 10.0), ("m1", "cpsat", 1, 10.0),
        ("m2", "cpsat", 0, 24.0), ("m2", "cpsat", 1, 24.0),
    ]  # fmt: skip
    bks = {"m1": 10.0, "m2": 20.0}
    cols = ("instance", "label", "seed", "makespan")
    df = pd.DataFrame([dict(zip(cols, r, strict=True)) for r in data])
    df["family"], df["time_limit"] = "b", 10.0
    df["best_known"] = df["instance"].map(bks)
    t = A.seed_spread_table(df)
    assert "| m1 | 10 | 10 11 | 10.5 (10-11) | 10 10 | 10.0 (10-10) |" in t
    assert "| 0 | 0.00% | 10.00% |" in t and "| 1 | 5.00% | 10.00% |" in t
    assert "- **tree**: mean gap 2.50% over the seeds (from 0.00% to 5.00%)" in t
    assert "the best seed of each instance: 0.00%; every seed at the best known on 1 of 2" in t
    assert "- **cpsat**: mean gap 10.00%" in t and "on 1 of 2 instances" in t
    # only the solvers that ran are columns; none at all is an error that names the table
    assert "cpsat" not in A.seed_spread_table(df[df["label"] == "tree"])
    with pytest.raises(UsageError, match=r"seed_spread_table: no runs of the solvers \['greedy'\]"):
        A.seed_spread_table(df[df["label"] == "tree"], solvers=("greedy",))
