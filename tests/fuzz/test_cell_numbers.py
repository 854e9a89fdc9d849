"""Property: any value in any numeric field of a cell file is refused by name or works.

Extremes included (0, -0, denormals, 1e-300, 1e300, ±inf, nan, 2**63,
10**30): :func:`workcell.cell.cell_from_dict` either builds the cell or
raises an error of ours naming the file and the field; compiling the built
cell (with a 2-task set) raises nothing else either. Values of fields whose
physical range the cell file does not check yet
(:data:`tests.fuzz.targets.PENDING_RANGES`) are left out of the compile
property; they are listed there with their reproducers.
"""

from __future__ import annotations

import contextlib
import re
from pathlib import Path

import pytest
from hypothesis import assume, given, settings

from multiarm.errors import InfeasibleError, MultiarmError
from tests.fuzz.targets import PENDING_RANGES, compile_tasks_file
from tests.strategies import cell_number_edits, numeric_cell_data, with_edits
from workcell import compile_cell
from workcell.cell import cell_from_dict

FIELD = re.compile(r"^c\.toml: (arms\.[gs]|compile)\b")


@settings(max_examples=100)
@given(edits=cell_number_edits())
def test_cell_numbers_are_refused_by_name_or_accepted(
    edits: list[tuple[tuple[str | int, ...], float | int]], tmp_path_factory: pytest.TempPathFactory
) -> None:
    folder: Path = tmp_path_factory.getbasetemp()
    data = with_edits(numeric_cell_data(), edits)
    data["tasks"] = compile_tasks_file(folder).name
    try:
        cell_from_dict(data, filename="c.toml", base_dir=folder)
    except MultiarmError as exc:
        # the field changed, or one it invalidates (a start outside new rails)
        assert FIELD.match(str(exc)), str(exc)


def test_a_refused_number_names_its_field() -> None:
    data = with_edits(numeric_cell_data(), [(("arms", "s", "link_lengths", 0), float("nan"))])
    with pytest.raises(MultiarmError, match=r"c\.toml: arms\.s\.link_lengths"):
        cell_from_dict(data, filename="c.toml")


def _pending(edits: list[tuple[tuple[str | int, ...], float | int]]) -> bool:
    for path, value in edits:
        key = tuple(str(p) for p in path)
        for field, (lo, hi) in PENDING_RANGES.items():
            if key == tuple(f for f in field if f) and lo < value < hi:
                return True
    return False


@settings(max_examples=20)
@given(edits=cell_number_edits(max_edits=2))
def test_compiling_a_cell_with_extreme_numbers_raises_only_our_errors(
    edits: list[tuple[tuple[str | int, ...], float | int]], tmp_path_factory: pytest.TempPathFactory
) -> None:
    assume(not _pending(edits))
    folder: Path = tmp_path_factory.getbasetemp()
    data = with_edits(numeric_cell_data(), edits)
    data["tasks"] = compile_tasks_file(folder).name
    try:
        cell = cell_from_dict(data, filename="c.toml", base_dir=folder)
    except MultiarmError:
        return  # the property above checks these messages
    # an infeasible cell names the task and why each arm cannot do it
    with contextlib.suppress(InfeasibleError):
        compile_cell(cell)


@pytest.mark.parametrize("size", [1e-300, 5e-324, 1e-12])
def test_a_tiny_space_grid_is_refused_by_its_block_count(size: float) -> None:
    """Finding of the property above (``compile.grid = 1e-300``): the block
    indices overflowed int64 and the grid became one block with empty bounds,
    an SDL error about ``<string>``. Now the count is taken in floats, and
    the cell file refuses grids under 1 cm by their field."""
    import numpy as np

    from multiarm.errors import ValidationError
    from workcell.geometry.reach import MAX_BLOCKS, shared_blocks

    boxes = [np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]), np.array([[0.5, 0.5, 0.5], [2.0, 2, 2]])]
    with pytest.raises(ValidationError, match=rf"more than {MAX_BLOCKS} blocks"):
        shared_blocks(boxes, size)
    assert shared_blocks(boxes, 0.25).n_zones == 27  # blocks 2..4 on each axis
    data = with_edits(numeric_cell_data(), [(("compile", "grid"), size)])
    with pytest.raises(MultiarmError, match=r"^c\.toml: compile\.grid: must be 0 \(off\) or in"):
        cell_from_dict(data, filename="c.toml")
