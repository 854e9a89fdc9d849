"""Problem factories of a sweep: FJSP files, generated problems, built-in cells and cell files."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from multiarm.errors import UsageError
from scheduler import read_fjsp
from scheduler.generate import random_problem
from workcell.cell import EXAMPLES, load_cell, load_example
from workcell.compile import compile_cell
from workcell.experiments.grid import InstanceSpec

if TYPE_CHECKING:
    from scheduler import Problem

__all__ = ["benchmark_function", "build_problem"]


@lru_cache(maxsize=32)
def build_problem(instance: InstanceSpec) -> Problem:
    """The scheduling problem of ``instance``, built once per process and cached.

    Built-in cells and cell files are compiled (FCL sweeps, travel setups,
    the blocking oracle); FJSP files are read; generated problems come from
    :func:`scheduler.generate.random_problem` with the instance's seed.

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
        return random_problem(
            p.pop("arms"), p.pop("tasks"), p.pop("zones"), p.pop("tools"), seed=instance.seed, **p
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
