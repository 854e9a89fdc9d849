"""Renamed names keep their old path for one release, warn, and hand on the new object
(issue 20: names that mean one thing)."""

from __future__ import annotations

import importlib

import pytest


@pytest.mark.parametrize(
    ("old", "new", "name"),
    [
        ("workcell.geometry.sweep", "workcell.geometry.zone_sweep", "zone_windows"),
        ("workcell.geometry.sweep", "workcell.geometry.zone_sweep", "_segments"),
        ("workcell.geometry._sweep_jit", "workcell.geometry._zone_sweep_jit", "capsules_touch"),
        ("scheduler.kernel", "scheduler.kernel", "compile_problem"),
    ],
)
def test_an_old_path_warns_and_hands_on_the_new_object(old: str, new: str, name: str) -> None:
    old_name = "compiled" if old == "scheduler.kernel" else name
    with pytest.warns(DeprecationWarning, match=f"{old}.{old_name} is deprecated"):
        value = getattr(importlib.import_module(old), old_name)
    assert value is getattr(importlib.import_module(new), name)


def test_an_unknown_name_is_still_an_attribute_error() -> None:
    import scheduler.kernel
    import workcell.geometry.sweep

    with pytest.raises(AttributeError):
        _ = workcell.geometry.sweep.no_such_name
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        _ = scheduler.kernel.no_such_name


def test_the_new_names_do_not_warn() -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        from scheduler.generate import random_problem
        from scheduler.kernel import compile_problem
        from workcell.geometry.zone_sweep import zone_windows

        p = random_problem(2, 4, 1, 0, seed=1)
        assert compile_problem(p).n_tasks == p.n_tasks and callable(zone_windows)


OLD_PATHS = (
    "workcell.sim.kernel",
    "workcell.sim.medium",
    "workcell.sim.network",
    "workcell.sim.faults",
    "workcell.sim.options",
    "workcell.sim.run",
    "workcell.sim.supersigma",
    "workcell.sim.harness.result",
    "workcell.geometry.sweep",
    "workcell.geometry._sweep_jit",
)
"""Module paths kept only for users' old code (they warn when imported or used)."""


def test_the_package_itself_uses_no_moved_module_path() -> None:
    """The command line's medium check once imported ``workcell.sim.network``, a
    path kept only for users' old code, so every ``--network`` run warned about
    the package's own import. In a fresh interpreter (no module cached), every
    module of the five packages but the old paths imports, and the medium
    check runs, without a "moved to" or "is deprecated" warning."""
    import subprocess
    import sys

    # the modules are listed from the files (pkgutil.walk_packages would import
    # every subpackage, the old ones too), then imported while warnings are kept
    code = (
        "import importlib, importlib.util, os, pkgutil, warnings\n"
        f"old = {OLD_PATHS!r}\n"
        "def walk(path, prefix):\n"
        "    for info in pkgutil.iter_modules(path):\n"
        "        name = prefix + info.name\n"
        "        if any(name == o or name.startswith(o + '.') for o in old):\n"
        "            continue\n"
        "        yield name\n"
        "        if info.ispkg:\n"
        "            yield from walk([os.path.join(p, info.name) for p in path], name + '.')\n"
        "names = []\n"
        "for pkg in ('multiarm', 'tasklib', 'zones', 'scheduler', 'workcell'):\n"
        "    spec = importlib.util.find_spec(pkg)\n"
        "    names += [pkg, *walk(list(spec.submodule_search_locations), pkg + '.')]\n"
        "with warnings.catch_warnings(record=True) as got:\n"
        "    warnings.simplefilter('always')\n"
        "    for name in names:\n"
        "        importlib.import_module(name)\n"
        "    from workcell.cli.args import check_network\n"
        "    check_network('ideal')\n"
        "print(len(names), [str(w.message) for w in got\n"
        "    if 'moved to' in str(w.message) or 'is deprecated' in str(w.message)])\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=300
    )
    count, warned = out.stdout.strip().split(" ", 1)
    assert int(count) > 150  # the walk found the package's modules
    assert warned == "[]", warned
