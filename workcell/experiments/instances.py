"""Problem factories of a sweep: FJSP files, generated problems, built-in cells and cell files."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Sequence
from functools import lru_cache
from pathlib import Path
from typing import Any

from multiarm.errors import UsageError
from scheduler import Problem, read_fjsp
from scheduler.generate import generate_problem
from workcell.cell import EXAMPLES, load_cell, load_example
from workcell.compile import compile_cell
from workcell.experiments.grid import InstanceSpec

__all__ = [
    "CAMPAIGN_BATCH",
    "CAMPAIGN_FUNCTION",
    "benchmark_function",
    "build_problem",
    "campaign_instances",
]

CAMPAIGN_FUNCTION = "workcell.campaign:campaign_batch"
"""The measurement function of a fault campaign's sweep runs (:mod:`workcell.campaign`)."""

CAMPAIGN_BATCH = 25
"""Episodes per sweep run of a campaign by default."""


@lru_cache(maxsize=32)
def build_problem(instance: InstanceSpec) -> Problem:
    """The scheduling problem of ``instance``, built once per process and cached.

    Built-in cells and cell files are compiled (FCL sweeps, travel setups,
    the blocking oracle); FJSP files are read; generated problems come from
    :func:`scheduler.generate.generate_problem` (the instance's ``generator``,
    default ``zones``: :func:`~scheduler.generate.random_problem`) with the instance's seed.

    Parameters
    ----------
    instance : InstanceSpec

    Returns
    -------
    scheduler.Problem
    """
    if instance.kind == "fjsp":
        path = Path(instance.source)
        return read_fjsp(path if path.is_absolute() else Path(instance.base_dir) / path)
    if instance.kind == "generated":
        p = dict(instance.params)
        p.pop("waits", None)  # how the problem is solved (see runner), not made
        return generate_problem(
            p.pop("generator", "zones"),
            p.pop("arms"),
            p.pop("tasks"),
            p.pop("zones"),
            p.pop("tools"),
            seed=instance.seed,
            **p,
        )
    if instance.source in EXAMPLES:
        return compile_cell(load_example(instance.source)).problem
    path = Path(instance.source)
    return compile_cell(
        load_cell(path if path.is_absolute() else Path(instance.base_dir) / path)
    ).problem


def _import_path(path: str) -> None:
    """Make ``path`` importable (benchmark functions live beside the sweep file)."""
    if path and path not in sys.path:
        sys.path.insert(0, path)


def benchmark_function(instance: InstanceSpec) -> Callable[..., Any]:
    """The measurement function of a ``benchmark`` instance (imported by name).

    Parameters
    ----------
    instance : InstanceSpec
        Of kind ``benchmark``: ``source`` is ``module:function`` and
        ``base_dir`` the directory the module is imported from.

    Returns
    -------
    callable

    Raises
    ------
    UsageError
        The module cannot be imported or has no such function.
    """
    module, _, attr = instance.source.partition(":")
    _import_path(instance.base_dir)
    try:
        mod = importlib.import_module(module)
    except ImportError as exc:
        raise UsageError(
            f"benchmark {instance.source!r}: cannot import {module!r}: {exc}"
        ) from None
    fn = getattr(mod, attr, None)
    if not callable(fn):
        raise UsageError(f"benchmark {instance.source!r}: {module!r} has no function {attr!r}")
    return fn  # type: ignore[no-any-return]


def campaign_instances(
    cells: Sequence[str],
    episodes: int,
    seeds: Sequence[int] = (0,),
    batch: int = CAMPAIGN_BATCH,
    family: str = "campaign",
) -> list[Any]:
    """The sweep instances (kind ``benchmark``) of a campaign: one per batch.

    Parameters
    ----------
    cells : sequence of str
    episodes : int
        Per cell and seed.
    seeds : sequence of int
        Campaign seeds.
    batch : int
        Episodes per run.
    family : str
        The instances' family label.

    Returns
    -------
    list of InstanceSpec

    Raises
    ------
    UsageError
        No cell, or a count out of range.
    """
    if not cells:
        raise UsageError("campaign: needs at least one cell")
    for name, v, least in (("episodes", episodes, 1), ("batch", batch, 1)):
        if isinstance(v, bool) or not isinstance(v, int) or v < least:
            raise UsageError(f"campaign: {name} must be an integer >= {least}, got {v!r}")
    for s in seeds:
        if isinstance(s, bool) or not isinstance(s, int) or s < 0:
            raise UsageError(f"campaign: seeds must be integers >= 0, got {s!r}")
    out = []
    for cell in cells:
        for s in seeds:
            for first in range(0, episodes, batch):
                n = min(batch, episodes - first)
                out.append(
                    InstanceSpec(
                        "benchmark",
                        family,
                        f"{Path(cell).stem}-s{s}-e{first}",
                        source=CAMPAIGN_FUNCTION,
                        params=(("cell", cell), ("count", n), ("first", first)),
                        seed=int(s),
                        base_dir="",
                    )
                )
    return out
