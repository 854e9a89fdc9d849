"""A solve that may race CP-SAT imports OR-Tools before its clock starts.

The racing thread used to import ``ortools.sat.python.cp_model`` itself,
inside the budget (about 0.4 s, longer from a cold disk), while loading its
extension modules held the interpreter (docs/scheduler.md, "Portfolio").
The order of the two events is checked in a fresh process, so nothing
imported earlier by the suite hides it.
"""

from __future__ import annotations

import json
import subprocess
import sys

_CHILD = r"""
import json, sys
import scheduler.tree as tree
from scheduler import solve
from scheduler.generate import random_problem
from scheduler.tree import TreeOptions

events = []
real_begin = tree.begin

def begin(*args, **kwargs):
    events.append(("clock", "ortools.sat.python.cp_model" in sys.modules))
    return real_begin(*args, **kwargs)

tree.begin = begin
p = random_problem(2, 8, 3, 1, seed=0)
# a work limit never races: nothing to import
solve(p, "tree", time_limit=None, seed=0, options=TreeOptions(max_evaluations=50))
# a wall-clock limit may race: OR-Tools is loaded when the clock starts
r = solve(p, "tree", time_limit=0.5, seed=0)
events.append(("raced", "portfolio" in r.stats.extra))
print(json.dumps(events))
"""


def test_a_solve_that_may_race_loads_or_tools_before_its_clock_starts() -> None:
    out = subprocess.run(
        [sys.executable, "-c", _CHILD], capture_output=True, text=True, timeout=120, check=True
    )
    events = json.loads(out.stdout.strip().splitlines()[-1])
    assert events == [["clock", False], ["clock", True], ["raced", True]]
