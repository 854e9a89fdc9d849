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

import re
from os import PathLike, fspath
from pathlib import Path

from multiarm.errors import FormatError, MultiarmError
from scheduler.problem import MAX_TIME, Model, Problem

__all__ = ["MAX_MACHINES", "parse_fjsp", "read_fjsp"]

MAX_MACHINES = 10_000
"""The most machines a header may announce (each becomes an arm)."""

_TOKEN = re.compile(r"\S+")
_INT = re.compile(r"[+-]?[0-9]+")


class _Tok:
    """An integer of the file with its 1-based line and column."""

    __slots__ = ("column", "line", "text", "value")

    def __init__(self, text: str, line: int, column: int, filename: str | None) -> None:
        self.text, self.line, self.column = text, line, column
        if not _INT.fullmatch(text):
            raise FormatError(
                f"{text[:20]!r} is not an integer", filename=filename, line=line, column=column
            )
        # at most 20 digits: more is corrupt for any FJSP value, and int() of
        # thousands of digits is refused by Python anyway
        if len(text.lstrip("+-")) > 20:
            raise FormatError(
                f"{text[:20]}... is far too large", filename=filename, line=line, column=column
            )
        self.value = int(text)


def parse_fjsp(text: str, name: str = "fjsp", filename: str | None = None) -> Problem:
    """Parse FJSPLIB text (see :func:`read_fjsp`).

    Parameters
    ----------
    text : str
        The file's content.
    name : str
        The problem's name.
    filename : str or None
        Shown in errors (``<string>`` when None).

    Returns
    -------
    Problem
        Machines ``M1..Mn`` as arms, operations ``Jj.Oo`` chained per job.

    Raises
    ------
    FormatError
        Anything malformed, with ``filename:line:column``.

    Examples
    --------
    >>> parse_fjsp("1 2\\n1 1 2 5\\n").task_names
    ('J1.O1',)
    >>> parse_fjsp("1 2\\n1 1 3 5\\n", filename="a.fjs")
    Traceback (most recent call last):
    ...
    multiarm.errors.FormatError: a.fjs:2:5: job 1 operation 1: machine 3 outside 1..2
    """
    if not isinstance(text, str):
        raise FormatError(f"FJSP text must be a str, got {type(text).__name__}", filename=filename)

    def err(msg: str, tok: _Tok | None = None, line: int | None = None) -> FormatError:
        if tok is not None:
            return FormatError(msg, filename=filename, line=tok.line, column=tok.column)
        return FormatError(msg, filename=filename, line=line)

    raw = [
        (i, [(mt.group(), mt.start() + 1) for mt in _TOKEN.finditer(ln)])
        for i, ln in enumerate(text.splitlines(), start=1)
    ]
    raw = [(i, toks) for i, toks in raw if toks]
    if not raw:
        raise FormatError("empty FJSP file", filename=filename)
    hline, hraw = raw[0]
    if len(hraw) < 2:
        raise err("the header needs the number of jobs and of machines", line=hline)
    # the header's third value (average machines per operation) is informational: ignored
    jobs_tok, mach_tok = (_Tok(x, hline, c, filename) for x, c in hraw[:2])
    lines = [(i, [_Tok(x, i, c, filename) for x, c in toks]) for i, toks in raw[1:]]
    n_jobs, n_mach = jobs_tok.value, mach_tok.value
    if n_jobs < 1:
        raise err(f"the header says {n_jobs} jobs (needs >= 1)", jobs_tok)
    if not 1 <= n_mach <= MAX_MACHINES:
        raise err(f"the header says {n_mach} machines (needs 1..{MAX_MACHINES})", mach_tok)
    if len(lines) != n_jobs:
        raise err(
            f"the header announces {n_jobs} jobs but the file has {len(lines)} job lines",
            jobs_tok,
        )
    m = Model(name)
    for k in range(1, n_mach + 1):
        m.add_arm(f"M{k}")
    for j, (i, vals) in enumerate(lines, start=1):
        pos = 0
        n_ops = vals[pos].value
        if n_ops < 1:
            raise err(f"job {j} has {n_ops} operations (needs >= 1)", vals[pos])
        pos += 1
        prev = None
        for o in range(1, n_ops + 1):
            if pos >= len(vals):
                raise err(f"job {j} ends before operation {o} of {n_ops}", line=i)
            k_tok = vals[pos]
            k = k_tok.value
            pos += 1
            if k < 1 or k > n_mach:
                raise err(f"job {j} operation {o}: {k} machines (needs 1..{n_mach})", k_tok)
            if pos + 2 * k > len(vals):
                raise err(
                    f"job {j} operation {o}: {k} machine/time pairs announced, "
                    f"{(len(vals) - pos) // 2} given",
                    k_tok,
                )
            t = m.add_task(
                f"J{j}.O{o}", predecessors=[prev] if prev is not None else [], group=j - 1
            )
            seen = set()
            for _ in range(k):
                mach_t, dur_t = vals[pos], vals[pos + 1]
                mach, dur = mach_t.value, dur_t.value
                pos += 2
                if not 1 <= mach <= n_mach:
                    raise err(f"job {j} operation {o}: machine {mach} outside 1..{n_mach}", mach_t)
                if mach in seen:
                    raise err(f"job {j} operation {o}: machine {mach} listed twice", mach_t)
                if dur <= 0:
                    raise err(f"job {j} operation {o}: time {dur} must be > 0", dur_t)
                if dur > MAX_TIME:
                    raise err(
                        f"job {j} operation {o}: time {dur} is beyond the largest the solvers "
                        f"handle ({MAX_TIME:g})",
                        dur_t,
                    )
                seen.add(mach)
                m.add_mode(t, mach - 1, float(dur))
            prev = t
        if pos != len(vals):
            raise err(f"job {j} has {len(vals) - pos} values left over (corrupt line)", vals[pos])
    try:
        return m.build()
    except MultiarmError as exc:  # a cross-record check: still name the file
        raise FormatError(str(exc), filename=filename) from None


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
