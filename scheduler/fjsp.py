"""Read FJSPLIB ``.fjs`` files (flexible job shop) into problems with no zones.

With zone constraints off, a multi-arm problem is an FJSP: arm = machine,
elementary task = operation, and a job's operations form a chain. The
format (``../shared/data/fjsp/README.md``): a header ``jobs machines avg``
(the third value is informational and often wrong: ignored), then one line
per job: ``n_ops`` then per operation ``k`` followed by ``k`` pairs
``machine time`` with 1-based machines. Values are separated by any spaces
or tabs; CRLF line endings, trailing whitespace and blank lines are fine;
machines that no operation uses are kept (as arms that get no task).

Examples
--------
>>> p = parse_fjsp("2 3 1.5\\r\\n2  1 1 5  2 1 3 2 2\\r\\n1 1 2 4\\r\\n")
>>> p.n_arms, p.n_tasks, p.task_names
(3, 3, ('J1.O1', 'J1.O2', 'J2.O1'))
"""

from __future__ import annotations

from os import PathLike, fspath
from pathlib import Path

from multiarm.errors import FormatError
from scheduler.problem import Model, Problem

__all__ = ["parse_fjsp", "read_fjsp"]


def parse_fjsp(text: str, name: str = "fjsp", filename: str | None = None) -> Problem:
    """Parse FJSPLIB text (see :func:`read_fjsp`)."""
    lines = [(i, ln.split()) for i, ln in enumerate(text.splitlines(), start=1)]
    lines = [(i, toks) for i, toks in lines if toks]
    if not lines:
        raise FormatError("empty FJSP file", filename=filename)

    def ints(i: int, toks: list[str]) -> list[int]:
        out = []
        for tok in toks:
            try:
                out.append(int(tok))
            except ValueError:
                raise FormatError(f"{tok!r} is not an integer", filename=filename, line=i) from None
        return out

    hline, header = lines[0]
    if len(header) < 2:
        raise FormatError(
            "the header needs the number of jobs and of machines", filename=filename, line=hline
        )
    n_jobs, n_mach = ints(hline, header[:2])
    if n_jobs < 1 or n_mach < 1:
        raise FormatError(
            f"the header says {n_jobs} jobs and {n_mach} machines", filename=filename, line=hline
        )
    if len(lines) - 1 != n_jobs:
        raise FormatError(
            f"the header announces {n_jobs} jobs but the file has {len(lines) - 1} job lines",
            filename=filename,
            line=hline,
        )
    m = Model(name)
    for k in range(1, n_mach + 1):
        m.add_arm(f"M{k}")
    for j, (i, toks) in enumerate(lines[1:], start=1):
        vals = ints(i, toks)
        pos = 0
        n_ops = vals[pos]
        pos += 1
        prev = None
        for o in range(1, n_ops + 1):
            if pos >= len(vals):
                raise FormatError(
                    f"job {j} ends before operation {o} of {n_ops}", filename=filename, line=i
                )
            k = vals[pos]
            pos += 1
            if k < 1 or pos + 2 * k > len(vals):
                raise FormatError(
                    f"job {j} operation {o}: bad number of machines {k}", filename=filename, line=i
                )
            t = m.add_task(
                f"J{j}.O{o}", predecessors=[prev] if prev is not None else [], group=j - 1
            )
            seen = set()
            for _ in range(k):
                mach, dur = vals[pos], vals[pos + 1]
                pos += 2
                if not 1 <= mach <= n_mach:
                    raise FormatError(
                        f"job {j} operation {o}: machine {mach} outside 1..{n_mach}",
                        filename=filename,
                        line=i,
                    )
                if mach in seen:
                    raise FormatError(
                        f"job {j} operation {o}: machine {mach} listed twice",
                        filename=filename,
                        line=i,
                    )
                if dur <= 0:
                    raise FormatError(
                        f"job {j} operation {o}: time {dur} must be > 0", filename=filename, line=i
                    )
                seen.add(mach)
                m.add_mode(t, mach - 1, float(dur))
            prev = t
        if pos != len(vals):
            raise FormatError(
                f"job {j} has {len(vals) - pos} values left over (corrupt line)",
                filename=filename,
                line=i,
            )
    return m.build()


def read_fjsp(path: str | PathLike[str]) -> Problem:
    """Read an FJSPLIB ``.fjs`` file into a :class:`Problem`.

    Machines become arms ``M1..Mn``, operations tasks ``Jj.Oo`` chained per
    job (the job index is the task's group); no zones, no setup times.

    Raises
    ------
    FormatError
        With the file and line of the problem.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="ascii", errors="strict")
    except OSError as exc:
        raise FormatError(f"cannot read FJSP file: {exc.strerror}", filename=fspath(path)) from None
    except UnicodeDecodeError:
        raise FormatError("FJSP files are ASCII text", filename=fspath(path)) from None
    return parse_fjsp(text, name=p.stem, filename=fspath(path))
