"""Where a run comes from: package version, git commit, dependencies, machine.

Every results row carries these columns (:data:`~workcell.experiments.rows.COLUMNS`),
so a table in ``benchmarks/results/`` says what produced it.
"""

from __future__ import annotations

import json
import os
import platform
import socket
import subprocess
from functools import lru_cache
from importlib import metadata
from pathlib import Path
from typing import Any

from multiarm import __version__

__all__ = ["DEPENDENCIES", "provenance"]

DEPENDENCIES = (
    "numpy",
    "numba",
    "ortools",
    "python-fcl",
    "ompl",
    "trimesh",
    "scipy",
    "lark",
    "pandas",
    "pyarrow",
    "dask",
    "distributed",
)
"""Distributions whose versions each row records."""


@lru_cache(maxsize=1)
def provenance() -> dict[str, Any]:
    """Where this process's runs come from (computed once per process).

    Returns
    -------
    dict
        ``package_version``, ``git_commit`` (of the checkout the package
        runs from, ``""`` outside one), ``dependencies`` (JSON), ``python``,
        ``platform``, ``host``, ``cpus``, ``pid``.
    """
    deps: dict[str, str | None] = {}
    for name in DEPENDENCIES:
        try:
            deps[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            deps[name] = None
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            check=False,
            cwd=Path(__file__).resolve().parent,
            timeout=10,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            check=False,
            cwd=Path(__file__).resolve().parent,
            timeout=10,
        ).stdout.strip()
        if commit and dirty:
            commit += "+dirty"
    except (OSError, subprocess.SubprocessError):
        commit = ""
    return {
        "package_version": __version__,
        "git_commit": commit,
        "dependencies": json.dumps(deps, sort_keys=True),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "host": socket.gethostname(),
        "cpus": os.cpu_count() or 0,
        "pid": os.getpid(),
    }
