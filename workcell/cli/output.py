"""What every command prints: tables, status lines, progress, exit statuses.

Exit statuses of ``multiarm`` (docs/cli.md has the table):

* 0 (:data:`EXIT_OK`): done; for ``check``, also a file with warnings only;
* 1 (:data:`EXIT_ERROR`): an error, printed as one line ``error: ...`` (bad
  input named by its file, field or option; no schedule found; a run stopped
  by the safety monitor);
* 2 (:data:`EXIT_USAGE`): the command line itself is malformed (argparse);
* 3 (:data:`EXIT_FAILURES`): the work ran but did not all succeed: tasks
  failed in a simulated run (unless ``--allow-failures``), findings of a
  campaign, failed runs of a sweep;
* 130 (:data:`EXIT_INTERRUPTED`): Ctrl-C, one line on stderr.

Progress goes to stderr: a bar on a terminal, and when stderr is not a
terminal (piped, a log file, CI) one line per step with the time elapsed,
so that a slow step is never silent.

Examples
--------
>>> print_table([{"a": 1, "bb": "x"}], ["a", "bb"])
a  bb
-  --
1  x
>>> status_line(0, 10)
'status: ok, 10 of 10 tasks done'
>>> status_line(3, 10)
'status: tasks failed, 3 of 10 tasks failed'
"""

from __future__ import annotations

import sys
import time
from collections.abc import Mapping, Sequence
from types import TracebackType
from typing import Protocol, TextIO

__all__ = [
    "EXIT_ERROR",
    "EXIT_FAILURES",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_USAGE",
    "Progress",
    "print_table",
    "status_line",
]

EXIT_OK = 0
"""Done (``check``: clean, or warnings only)."""
EXIT_ERROR = 1
"""An error of the package's family, printed as one line."""
EXIT_USAGE = 2
"""A malformed command line (argparse's own status)."""
EXIT_FAILURES = 3
"""The work ran but not all of it succeeded: failed tasks, campaign
findings, failed sweep runs."""
EXIT_INTERRUPTED = 130
"""Ctrl-C (128 + SIGINT, the shell's convention)."""


def print_table(
    rows: Sequence[Mapping[str, object]], columns: Sequence[str], file: TextIO | None = None
) -> None:
    """Print ``rows`` as a left-aligned text table with a header and a rule.

    Parameters
    ----------
    rows : sequence of mappings
        One mapping a row; every column must be a key (values shown with ``str``).
    columns : sequence of str
        Column names, in order.
    file : text stream, optional
        Default ``sys.stdout``.
    """
    out = file if file is not None else sys.stdout
    table = [[str(r[c]) for c in columns] for r in rows]
    widths = [max(len(c), *(len(row[i]) for row in table)) for i, c in enumerate(columns)]
    lines = [
        "  ".join(c.ljust(w) for c, w in zip(columns, widths, strict=True)),
        "  ".join("-" * w for w in widths),
        *("  ".join(v.ljust(w) for v, w in zip(row, widths, strict=True)) for row in table),
    ]
    print("\n".join(line.rstrip() for line in lines), file=out)


def status_line(failed: int, total: int) -> str:
    """The last line of a simulated run: ``status: ok`` or ``status: tasks failed``.

    Parameters
    ----------
    failed, total : int
        Tasks failed, and tasks of the problem.
    """
    if failed:
        return f"status: tasks failed, {failed} of {total} tasks failed"
    return f"status: ok, {total} of {total} tasks done"


class _Bar(Protocol):
    """The part of a tqdm bar used here."""

    def update(self, n: int = 1) -> object: ...
    def set_postfix_str(self, s: str = "") -> object: ...
    def close(self) -> None: ...


class Progress:
    """Progress of a command's steps on stderr.

    On a terminal, a tqdm bar; otherwise one line a step,
    ``[  12.3 s] name: step 2/5: solve (tree, ...)``, flushed at once.
    ``total`` may grow (:meth:`add`). Use as a context manager: the bar is
    closed on the way out, also after an error or Ctrl-C.

    Parameters
    ----------
    total : int
        Steps expected.
    name : str
        Prefix of each line (the cell, or the command).
    enabled : bool
        False: print nothing.
    stream : text stream, optional
        Default ``sys.stderr``.
    """

    def __init__(
        self, total: int, name: str, *, enabled: bool = True, stream: TextIO | None = None
    ) -> None:
        self.total = total
        self.name = name
        self.done = 0
        self.stream = stream if stream is not None else sys.stderr
        self.t0 = time.perf_counter()
        self.enabled = enabled
        self.tty = enabled and self.stream.isatty()
        self._bar: _Bar | None = None
        if self.tty:
            from tqdm import tqdm  # type: ignore[import-untyped,unused-ignore]

            self._bar = tqdm(total=total, desc=name, file=self.stream, leave=False, unit="step")

    def elapsed(self) -> float:
        """Seconds since the progress began."""
        return time.perf_counter() - self.t0

    def step(self, what: str) -> None:
        """A new step begins: ``what`` is shown (the previous step counts as done)."""
        if not self.enabled:
            return
        number = min(self.done + 1, max(self.total, 1))
        if self._bar is not None:
            if self.done:
                self._bar.update(1)
            self._bar.set_postfix_str(what)
        else:
            print(
                f"[{self.elapsed():8.1f} s] {self.name}: step {number}/{self.total}: {what}",
                file=self.stream,
                flush=True,
            )
        self.done += 1

    def close(self) -> None:
        """Close the bar (a no-op without one)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> Progress:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
