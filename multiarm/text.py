"""Helpers shared by the package's small languages (TDL, SDL) and data files.

Both languages are parsed with lark; this module turns lark's exceptions into
ours (with ``filename``, ``line``, ``column`` and readable expected tokens) and
prints numbers so that parsing the printed text gives back the same float.
:func:`parse_json` and :func:`parse_toml` do the same for the JSON and TOML
files (task sets, problems, schedules, sweeps): every way the standard
library's decoders fail (syntax, nesting too deep for the recursion limit, an
integer of more than 4300 digits) becomes our error naming the file.
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from os import PathLike, fspath
from pathlib import Path
from typing import Any

import lark
from lark.exceptions import (
    UnexpectedCharacters,
    UnexpectedEOF,
    UnexpectedInput,
    UnexpectedToken,
    VisitError,
)

from multiarm.errors import ParseError, SourceError

__all__ = [
    "fmt_float",
    "meta_location",
    "parse_json",
    "parse_text",
    "parse_toml",
    "quote",
    "read_source",
    "unquote",
]


def fmt_float(value: float) -> str:
    """Shortest text that reads back as exactly ``value``.

    Examples
    --------
    >>> fmt_float(0.1), fmt_float(2.0), fmt_float(-1e-300)
    ('0.1', '2', '-1e-300')
    """
    if not math.isfinite(value):
        raise ValueError(f"cannot print non-finite number {value!r}")
    if value == int(value) and abs(value) < 1e15:
        text = str(int(value))
        if value == 0 and math.copysign(1.0, value) < 0:
            return "-0.0"
        return text
    return repr(float(value))


def quote(text: str) -> str:
    """A double-quoted string literal with backslash escapes."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def unquote(token: str) -> str:
    """Inverse of :func:`quote` for a lark ESCAPED_STRING token."""
    body = token[1:-1]
    out = []
    i = 0
    while i < len(body):
        ch = body[i]
        if ch == "\\" and i + 1 < len(body):
            nxt = body[i + 1]
            out.append("\n" if nxt == "n" else nxt)
            i += 2
        else:
            out.append(ch)
            i += 1
    return "".join(out)


_FRIENDLY = {
    "NAME": "a name",
    "CNAME": "a name",
    "SIGNED_NUMBER": "a number",
    "NUMBER": "a number",
    "ESCAPED_STRING": "a quoted string",
}
_WORDS = re.compile(r"\(\?:((?:[A-Za-z_]+\|)*[A-Za-z_]+)\)\Z")


def _describe_terminal(parser: lark.Lark, name: str) -> list[str]:
    """Readable names for a terminal: its literal text, its keyword list, or a noun."""
    if name in ("$END", "<END-OF-FILE>"):
        return ["end of input"]
    if name in _FRIENDLY:
        return [_FRIENDLY[name]]
    try:
        term = parser.get_terminal(name)
    except KeyError:
        return [name]
    pattern = term.pattern
    if isinstance(pattern, lark.lexer.PatternStr):
        return [repr(pattern.value)]
    words = _WORDS.match(pattern.value)
    if words:
        return [repr(w) for w in words.group(1).split("|")]
    return [name.lower()]


def _end_position(text: str) -> tuple[int, int]:
    line = text.count("\n") + 1
    column = len(text) - (text.rfind("\n") + 1) + 1
    return line, column


def parse_text(
    parser: lark.Lark,
    text: str,
    filename: str | None,
    syntax_error: type[ParseError],
    transformer: Any = None,
) -> Any:
    """Parse ``text`` and, optionally, transform the tree.

    Lark exceptions become ``syntax_error`` (a :class:`ParseError` subclass)
    located at ``filename:line:column`` with the expected tokens by their
    literal text. An exception of ours raised inside the transformer is
    re-raised unchanged (not wrapped in lark's ``VisitError``).
    """
    if not isinstance(text, str):
        raise TypeError(f"expected text (str), got {type(text).__name__}")
    try:
        tree = parser.parse(text)
        if transformer is not None:
            return transformer.transform(tree)
        return tree
    except UnexpectedInput as exc:
        raise _convert(parser, text, filename, syntax_error, exc) from None
    except VisitError as exc:
        if isinstance(exc.orig_exc, SourceError):
            raise exc.orig_exc from None
        if isinstance(exc.orig_exc, RecursionError):
            raise syntax_error("the text is nested too deeply", filename=filename) from None
        raise
    except RecursionError:
        # the tree is transformed recursively: thousands of nested blocks
        raise syntax_error("the text is nested too deeply", filename=filename) from None


def _convert(
    parser: lark.Lark,
    text: str,
    filename: str | None,
    cls: type[ParseError],
    exc: UnexpectedInput,
) -> ParseError:
    line = getattr(exc, "line", None)
    column = getattr(exc, "column", None)
    if isinstance(exc, UnexpectedCharacters):
        pos: int | None = exc.pos_in_stream
        char = text[pos] if pos is not None and 0 <= pos < len(text) else ""
        message = f"unexpected character {char!r}"
        names: set[str] = set(exc.allowed or ())
    elif isinstance(exc, UnexpectedToken):
        token = exc.token
        if token.type == "$END":
            message = "unexpected end of input"
            line, column = _end_position(text)
        else:
            message = f"unexpected {token.value!r}"
        # ``accepts`` replays the parse to find what is really acceptable
        # here; ``expected`` carries LALR's merged look-aheads and can list
        # keywords that would not parse.
        try:
            names = set(exc.accepts or exc.expected or ())
        except Exception:  # pragma: no cover - defensive: fall back to LALR's set
            names = set(exc.expected or ())
    elif isinstance(exc, UnexpectedEOF):
        message = "unexpected end of input"
        line, column = _end_position(text)
        names = set(exc.expected or ())
    else:  # pragma: no cover - lark has no other subclass today
        message = str(exc)
        names = set()
    if line is None or line < 1:
        line, column = _end_position(text)
    expected = sorted({d for n in names for d in _describe_terminal(parser, n)})
    return cls(message, filename=filename, line=line, column=column, expected=expected)


def read_source(path: str | PathLike[str], error: type[SourceError], what: str) -> str:
    """The UTF-8 text of a source file; an unreadable or undecodable file
    raises ``error`` (e.g. ``TDLError``) naming the file."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise error(f"cannot read {what} file: {exc.strerror}", filename=fspath(path)) from None
    except UnicodeDecodeError as exc:
        raise error(
            f"{what} file is not UTF-8 text ({exc.reason})", filename=fspath(path)
        ) from None


def meta_location(meta: Any) -> tuple[int | None, int | None]:
    """(line, column) of a lark tree's meta, or (None, None) when empty."""
    if meta is None or getattr(meta, "empty", True):
        return None, None
    return meta.line, meta.column


_TOML_POS = re.compile(r"\(at line (\d+), column (\d+)\)")


def parse_json(text: str, filename: str | None, error: type[SourceError], what: str) -> Any:
    """The data of a JSON text; any failure raises ``error`` naming ``filename``.

    Parameters
    ----------
    text : str
    filename : str or None
        Named in errors (``<string>`` when None).
    error : type of SourceError
        The error raised (e.g. :class:`~multiarm.errors.FormatError`).
    what : str
        What the file holds, for the messages (``"problem file"``).

    Examples
    --------
    >>> from multiarm.errors import FormatError
    >>> parse_json('{"a": [1, 2]}', "p.json", FormatError, "problem file")
    {'a': [1, 2]}
    >>> parse_json('{"a": [1, 2}', "p.json", FormatError, "problem file")
    Traceback (most recent call last):
    ...
    multiarm.errors.FormatError: p.json:1:12: Expecting ',' delimiter
    >>> parse_json("[" * 100_000, "p.json", FormatError, "problem file")
    Traceback (most recent call last):
    ...
    multiarm.errors.FormatError: p.json: problem file is nested too deeply
    """
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise error(exc.msg, filename=filename, line=exc.lineno, column=exc.colno) from None
    except RecursionError:
        raise error(f"{what} is nested too deeply", filename=filename) from None
    except ValueError as exc:  # int(): more digits than sys.get_int_max_str_digits()
        raise error(
            f"{what} holds a number with too many digits ({exc})", filename=filename
        ) from None


def parse_toml(text: str, filename: str | None, error: type[SourceError], what: str) -> Any:
    """The data of a TOML text; any failure raises ``error`` at ``file:line:col``.

    Parameters
    ----------
    text : str
    filename : str or None
        Named in errors (``<string>`` when None).
    error : type of SourceError
        The error raised (e.g. :class:`~multiarm.errors.FormatError`).
    what : str
        What the file holds, for the messages (``"sweep file"``).

    Examples
    --------
    >>> from multiarm.errors import FormatError
    >>> parse_toml('name = "x"\\nzones = [', "c.toml", FormatError, "cell file")
    Traceback (most recent call last):
    ...
    multiarm.errors.FormatError: c.toml:2:10: TOML syntax error: Invalid value at the end of the file
    >>> parse_toml("n = " + "9" * 5000, "c.toml", FormatError, "cell file")
    Traceback (most recent call last):
    ...
    multiarm.errors.FormatError: c.toml: cell file holds a number with too many digits ...
    """
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg = str(exc)
        m = _TOML_POS.search(msg)
        line = int(m.group(1)) if m else None
        col = int(m.group(2)) if m else None
        if m is None and "end of document" in msg:
            lines = text.split("\n")
            line, col = len(lines), len(lines[-1]) + 1
            msg = msg.replace("(at end of document)", "at the end of the file")
        raise error(
            f"TOML syntax error: {_TOML_POS.sub('', msg).strip()}",
            filename=filename,
            line=line,
            column=col,
        ) from None
    except RecursionError:
        raise error(f"{what} is nested too deeply", filename=filename) from None
    except ValueError as exc:  # int(): more digits than sys.get_int_max_str_digits()
        raise error(
            f"{what} holds a number with too many digits ({exc})", filename=filename
        ) from None
