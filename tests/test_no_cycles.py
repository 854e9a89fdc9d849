"""No import circle among our modules, ``TYPE_CHECKING`` imports and imports
inside functions included (issue: one front door; DESIGN.md's one direction
of imports holds inside each package too)."""

from __future__ import annotations

import grimp

from tests.scheduler.test_no_cycles import find_cycle

PACKAGES = ("multiarm", "tasklib", "zones", "scheduler", "workcell")


def test_no_module_of_ours_imports_itself_back() -> None:
    graph = grimp.build_graph(*PACKAGES, exclude_type_checking_imports=False, cache_dir=None)
    # (tests/scheduler/test_no_cycles.py shows the circle finder can fail)
    assert find_cycle(graph) == []
