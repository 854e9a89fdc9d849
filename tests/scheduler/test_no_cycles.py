"""The scheduler's modules import each other without a circle (issue: kernel <->
problem <-> schedule <-> setup <-> timing), and the problem never needs the kernel."""

from __future__ import annotations

import ast
from pathlib import Path

import grimp
import pytest

ROOT = Path(__file__).resolve().parents[2]


def find_cycle(graph: grimp.ImportGraph) -> list[str]:
    """A circle of direct imports in ``graph`` (empty: none)."""
    color: dict[str, int] = {}
    for start in sorted(graph.modules):
        if start in color:
            continue
        stack = [(start, iter(sorted(graph.find_modules_directly_imported_by(start))))]
        path = [start]
        color[start] = 1
        while stack:
            node, it = stack[-1]
            nxt = next(it, None)
            if nxt is None:
                color[node] = 2
                stack.pop()
                path.pop()
            elif color.get(nxt) == 1:
                return [*path[path.index(nxt) :], nxt]
            elif nxt not in color:
                color[nxt] = 1
                path.append(nxt)
                stack.append((nxt, iter(sorted(graph.find_modules_directly_imported_by(nxt)))))
    return []


@pytest.fixture(scope="module")
def graph() -> grimp.ImportGraph:
    # imports under ``if TYPE_CHECKING:`` are annotations only: they never run
    return grimp.build_graph("scheduler", exclude_type_checking_imports=True)


def test_the_scheduler_import_graph_has_no_circle(graph: grimp.ImportGraph) -> None:
    assert find_cycle(graph) == []


def test_the_circle_finder_can_fail() -> None:
    g = grimp.ImportGraph()
    for a, b in [("p.a", "p.b"), ("p.b", "p.c"), ("p.c", "p.a"), ("p.c", "p.d")]:
        g.add_import(importer=a, imported=b)
    assert find_cycle(g) == ["p.a", "p.b", "p.c", "p.a"]
    g.remove_import(importer="p.c", imported="p.a")
    assert find_cycle(g) == []


@pytest.mark.parametrize("module", ["problem", "setup", "timing", "schedule"])
def test_the_problem_side_never_imports_the_kernel(graph: grimp.ImportGraph, module: str) -> None:
    assert not graph.chain_exists(
        importer=f"scheduler.{module}", imported="scheduler.kernel", as_packages=True
    )


def test_no_scheduler_import_hides_inside_a_function() -> None:
    # a function-level import of a sibling module is how a circle hides; the
    # problem side and the kernel have none (numba is imported at the top)
    files = [ROOT / "scheduler" / f for f in ("problem.py", "setup.py", "timing.py", "schedule.py")]
    files += sorted((ROOT / "scheduler" / "kernel").glob("*.py"))
    hidden = []
    for f in files:
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                for sub in ast.walk(node):
                    if isinstance(sub, ast.ImportFrom) and (sub.module or "").startswith(
                        "scheduler"
                    ):
                        hidden.append(f"{f.name}:{sub.lineno} {sub.module}")
                    if isinstance(sub, ast.Import) and any(
                        a.name.startswith("scheduler") for a in sub.names
                    ):
                        hidden.append(f"{f.name}:{sub.lineno}")
    assert hidden == []
