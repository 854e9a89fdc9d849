"""FJSPLIB reader on every shared instance, and the lower bound against the best-known values."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from multiarm.errors import FormatError
from scheduler import lower_bound, lower_bounds, parse_fjsp, read_fjsp

SHARED = Path(os.environ.get("MULTIARM_SHARED", Path(__file__).resolve().parents[3] / "shared"))
DATA = SHARED / "data" / "fjsp"
if not DATA.is_dir():  # fail loudly: these instances are the external check of the scheduler
    raise RuntimeError(
        f"FJSP data not found at {DATA}: the project expects ../shared beside it "
        "(or MULTIARM_SHARED pointing at it)"
    )
# (jobs, machines, operations, alternatives per operation, best-known makespan), from
# ../shared/data/fjsp/README.md
TABLE = {
    "mk01": (10, 6, 55, 2.09, 40),
    "mk02": (10, 6, 58, 4.10, 26),
    "mk03": (15, 8, 150, 3.01, 204),
    "mk04": (15, 8, 90, 1.91, 60),
    "mk05": (15, 4, 106, 1.71, 172),
    "mk06": (10, 10, 150, 3.27, 57),
    "mk07": (20, 5, 100, 2.83, 139),
    "mk08": (20, 10, 225, 1.43, 523),
    "mk09": (20, 10, 240, 2.52, 307),
    "mk10": (20, 15, 240, 2.98, 193),
    "sfjs01": (2, 2, 4, 2.00, 66),
    "sfjs02": (2, 2, 4, 1.50, 107),
    "sfjs03": (3, 2, 6, 1.67, 221),
    "sfjs04": (3, 2, 6, 1.67, 355),
    "sfjs05": (3, 2, 6, 2.00, 119),
    "sfjs06": (3, 3, 9, 1.67, 320),
    "sfjs07": (3, 5, 9, 2.00, 397),
    "sfjs08": (3, 4, 9, 2.00, 253),
    "sfjs09": (3, 3, 9, 2.00, 210),
    "sfjs10": (4, 5, 12, 1.67, 516),
    "mfjs01": (5, 6, 15, 2.20, 468),
    "mfjs02": (5, 7, 15, 2.60, 446),
    "mfjs03": (6, 7, 18, 2.67, 466),
    "mfjs04": (7, 7, 21, 2.67, 554),
    "mfjs05": (7, 7, 21, 2.62, 514),
    "mfjs06": (8, 7, 24, 2.58, 634),
    "mfjs07": (8, 7, 32, 2.44, 879),
    "mfjs08": (9, 8, 36, 2.39, 884),
    "mfjs09": (11, 8, 44, 2.34, 1055),
    "mfjs10": (12, 8, 48, 2.33, 1196),
}


def path_of(name: str) -> Path:
    return DATA / ("brandimarte" if name.startswith("mk") else "fattahi") / f"{name}.fjs"


def test_every_shared_instance_is_covered() -> None:
    files = {p.stem for p in DATA.rglob("*.fjs")}
    assert files == set(TABLE)


@pytest.mark.parametrize("name", sorted(TABLE))
def test_reader_matches_the_published_counts(name: str) -> None:
    jobs, machines, ops, alts, _ = TABLE[name]
    p = read_fjsp(path_of(name))
    assert p.n_arms == machines and p.n_tasks == ops
    assert len(set(p.task_group.tolist())) == jobs
    assert p.n_modes / p.n_tasks == pytest.approx(alts, abs=0.006)
    assert not p.has_zones() and p.n_tools == 0
    # a job's operations form a chain
    for t in range(p.n_tasks):
        for q in p.task_preds[t]:
            assert p.task_group[q] == p.task_group[t]


@pytest.mark.parametrize("name", sorted(TABLE))
def test_lower_bound_never_exceeds_best_known(name: str) -> None:
    p = read_fjsp(path_of(name))
    lb = lower_bounds(p)
    assert lb.value <= TABLE[name][4] + 1e-9
    assert lb.value >= lb.critical_path and lb.value >= lb.load


def test_quirks_are_accepted() -> None:
    # CRLF, tabs, a float third header value that is wrong, trailing spaces, a blank last line,
    # and a machine (3) no operation uses
    text = "2\t3\t7.5 \r\n2  1 1 5  2 1 3 2 2\r\n1 1 2 4 \r\n\r\n"
    p = parse_fjsp(text)
    assert (p.n_arms, p.n_tasks) == (3, 3)
    assert p.task_modes[0] == (0,) and p.mode_duration[list(p.task_modes[1])].tolist() == [3.0, 2.0]
    assert p.task_preds == ((), (0,), ())
    assert not (p.mode_arm == 2).any()
    assert lower_bound(p) == 7.0  # job 1's chain: 5 + 2


@pytest.mark.parametrize(
    ("text", "message", "line"),
    [
        ("", "empty FJSP file", None),
        ("2\n1 1 1 3\n", "the header needs", 1),
        ("2 2 1\n1 1 1 3\n", "announces 2 jobs but the file has 1", 1),
        ("1 2 1\n1 1 3 3\n", "machine 3 outside 1..2", 2),
        ("1 2 1\n1 1 1 3 9\n", "1 values left over", 2),
        ("1 2 1\n2 1 1 3\n", "job 1 ends before operation 2", 2),
        ("1 2 1\n1 1 1 0\n", "time 0 must be > 0", 2),
        ("1 2 1\n1 2 1 3 1 4\n", "machine 1 listed twice", 2),
        ("1 2 1\n1 1 x 3\n", "'x' is not an integer", 2),
    ],
)
def test_corrupt_files_name_the_line(text: str, message: str, line: int | None) -> None:
    with pytest.raises(FormatError, match=message) as info:
        parse_fjsp(text, filename="bad.fjs")
    assert info.value.line == line and info.value.filename == "bad.fjs"


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(FormatError, match="cannot read"):
        read_fjsp(tmp_path / "none.fjs")
    (tmp_path / "u.fjs").write_bytes("1 1 1\n1 1 1 2 é\n".encode())
    with pytest.raises(FormatError, match="ASCII"):
        read_fjsp(tmp_path / "u.fjs")
    _ = np
