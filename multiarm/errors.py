"""The one exception root of the package and its families.

Every error the package raises on purpose derives from :class:`MultiarmError`,
so ``except MultiarmError`` catches everything of ours. The families say
*whose* problem it is:

* :class:`InputError` (also a :class:`ValueError`): the caller's input is
  wrong. Subfamilies: :class:`ValidationError` (records or problems that
  break a rule; the message names the culprit), :class:`SourceError` (an
  error located in a text file, with ``filename``, ``line`` and ``column``;
  :class:`ParseError` adds the tokens that were ``expected``) and
  :class:`UsageError` (an API called in the wrong state, e.g. a step added to
  a task already closed).
* :class:`InfeasibleError`: the input is well-formed but has no answer
  (:class:`NoFeasibleSchedule`, :class:`PlanningFailed`).
* :class:`InternalError` (also a :class:`RuntimeError`): a bug of ours; please
  report it.

Each language has its own pair (``TDLError``/``TDLSyntaxError``,
``SDLError``/``SDLSyntaxError``) so that a caller can catch "anything wrong
with this SDL file" in one clause.

Examples
--------
>>> from multiarm.errors import MultiarmError, SDLSyntaxError
>>> err = SDLSyntaxError("unexpected '}'", filename="cell.sdl", line=3, column=7,
...                      expected=("NAME",))
>>> str(err)
"cell.sdl:3:7: unexpected '}' (expected NAME)"
>>> isinstance(err, MultiarmError) and isinstance(err, ValueError)
True
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = [
    "CycleError",
    "FormatError",
    "InfeasibleError",
    "InputError",
    "InternalError",
    "MultiarmError",
    "NoFeasibleSchedule",
    "ParseError",
    "PlanningFailed",
    "SDLError",
    "SDLSyntaxError",
    "ScheduleError",
    "SourceError",
    "TDLError",
    "TDLSyntaxError",
    "Unreachable",
    "UsageError",
    "ValidationError",
]


class MultiarmError(Exception):
    """Root of every exception the package raises on purpose."""


# ----------------------------------------------------------------- bad input


class InputError(MultiarmError, ValueError):
    """The caller's input is wrong (data, files or arguments)."""


class ValidationError(InputError):
    """A record, task set, zone map or problem breaks one of its rules.

    The message names the culprit (task, part, zone, ...).
    """


class CycleError(ValidationError):
    """A dependency relation that must be acyclic has a cycle.

    Parameters
    ----------
    message : str
        What is wrong, naming the cycle.
    cycle : sequence of str
        The members of the cycle in order; the first is repeated at the end
        (``("a", "b", "a")``).
    """

    def __init__(self, message: str, cycle: Sequence[str]) -> None:
        super().__init__(message)
        self.cycle: tuple[str, ...] = tuple(cycle)

    def __reduce__(self) -> tuple[object, ...]:
        return (type(self), (self.args[0], self.cycle), self.__dict__)


class ScheduleError(ValidationError):
    """A schedule breaks a constraint of its problem (the message names it)."""


class UsageError(InputError):
    """An API was called in a state that does not allow it."""


class SourceError(InputError):
    """An error located in a text source (file or string).

    Parameters
    ----------
    message : str
        What is wrong, without the location.
    filename : str or None
        The file name, or ``None`` for text that came from a string
        (shown as ``<string>``).
    line, column : int or None
        1-based position of the culprit, when known.

    Attributes
    ----------
    message, filename, line, column
        As given. ``str(err)`` is ``"file:line:col: message"``.
    """

    def __init__(
        self,
        message: str,
        *,
        filename: str | None = None,
        line: int | None = None,
        column: int | None = None,
    ) -> None:
        self.message = message
        self.filename = filename
        self.line = line
        self.column = column
        super().__init__(self._render())

    def location(self) -> str:
        """``file:line:col`` (the parts that are known)."""
        where = self.filename if self.filename is not None else "<string>"
        if self.line is not None:
            where += f":{self.line}"
            if self.column is not None:
                where += f":{self.column}"
        return where

    def _render(self) -> str:
        return f"{self.location()}: {self.message}"

    def __reduce__(self) -> tuple[object, ...]:
        # Keyword-only constructors do not survive the default pickling of
        # exceptions (needed by multiprocessing and pytest-xdist).
        return (_rebuild, (type(self), dict(self.__dict__)))


def _rebuild(cls: type[SourceError], state: dict[str, object]) -> SourceError:
    obj = cls.__new__(cls)
    obj.__dict__.update(state)
    Exception.__init__(obj, obj._render())
    return obj


class ParseError(SourceError):
    """A syntax error: the text does not follow the grammar.

    Parameters
    ----------
    message : str
        What was found.
    expected : sequence of str
        Human-readable names of the tokens that would have been accepted.
    filename, line, column
        See :class:`SourceError`.
    """

    def __init__(
        self,
        message: str,
        *,
        filename: str | None = None,
        line: int | None = None,
        column: int | None = None,
        expected: Sequence[str] = (),
    ) -> None:
        self.expected: tuple[str, ...] = tuple(expected)
        super().__init__(message, filename=filename, line=line, column=column)

    def _render(self) -> str:
        text = super()._render()
        if self.expected:
            shown = ", ".join(self.expected[:12])
            if len(self.expected) > 12:
                shown += ", ..."
            text += f" (expected {shown})"
        return text


class FormatError(SourceError):
    """A data file (FJSP instance, task-set file, cell file) is malformed."""


class TDLError(SourceError):
    """Anything wrong with a TDL (trajectory description language) text."""


class TDLSyntaxError(TDLError, ParseError):
    """A TDL text does not follow the TDL grammar."""


class SDLError(SourceError):
    """Anything wrong with an SDL (subzone description language) text."""


class SDLSyntaxError(SDLError, ParseError):
    """An SDL text does not follow the SDL grammar."""


# ---------------------------------------------------------------- no answer


class InfeasibleError(MultiarmError):
    """The input is well-formed but admits no solution."""


class NoFeasibleSchedule(InfeasibleError):
    """No schedule satisfies the problem's constraints."""


class PlanningFailed(InfeasibleError):
    """The motion planner found no collision-free path."""


class Unreachable(InfeasibleError):
    """An arm cannot reach a pose: out of its workspace, or only beyond a joint limit.

    The message names the arm, the pose (or waypoint) and the reason.
    """


# -------------------------------------------------------------------- ours


class InternalError(MultiarmError, RuntimeError):
    """A bug in the package: an invariant of ours does not hold."""
