"""Field readers of the sweep file: each error names the file and the field path."""

from __future__ import annotations

import math
from collections.abc import Mapping
from os import fspath
from pathlib import Path
from typing import Any

from multiarm.errors import MultiarmError, ValidationError


class _Where:
    """Builds ``file: field.path: message`` errors."""

    def __init__(self, filename: str) -> None:
        self.filename = filename

    def fail(self, path: str, message: str) -> ValidationError:
        return ValidationError(f"{self.filename}: {path}: {message}" if path else message)


def _unknown(w: _Where, data: Mapping[str, Any], known: set[str], where: str) -> None:
    bad = sorted(set(data) - known)
    if bad:
        raise w.fail(
            f"{where}.{bad[0]}" if where else bad[0],
            f"unknown field (known: {', '.join(sorted(known))})",
        )


def _table(w: _Where, value: Any, where: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise w.fail(where, f"expected a table, got {type(value).__name__}")
    return value


def _list(w: _Where, value: Any, where: str) -> list[Any]:
    if not isinstance(value, list):
        raise w.fail(where, f"expected a list, got {value!r}")
    if not value:
        raise w.fail(where, "expected a non-empty list")
    return value


MAX_INT = 2**62
"""Largest integer field (seeds plus repetitions are stored as 64-bit integers)."""
MAX_RUNS = 100_000
"""Most runs one sweep file may hold (instances x solver seeds x repetitions):
a bigger grid is a typo (``repetitions = 1e9``) or weeks of work; split it."""
# The keys a generated instance may set, with their types (sweep files).
GENERATOR_KEYS: dict[str, type] = {
    "precedence": float,
    "release_fraction": float,
    "zone_fraction": float,
    "tool_fraction": float,
    "setups": bool,
    "start_zones": bool,
    "blocking": bool,
    "grid": int,
    "generator": str,
    "setup_fraction": float,
    "flexibility": float,
    "stay_fraction": float,
    "shared_fraction": float,
    "reach": int,
    "waits": bool,
}

MAX_GENERATED = (1_000, 10_000, 1_000, 1_000)
"""Largest arms, tasks, zones and tools of a generated instance."""


def _int(w: _Where, value: Any, where: str, least: int = 0, most: int = MAX_INT) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not least <= value <= most:
        above = isinstance(value, int) and not isinstance(value, bool) and value > most
        bound = f">= {least}" + (f" and <= {most}" if most != MAX_INT or above else "")
        raise w.fail(where, f"expected an integer {bound}, got {value!r}")
    return value


def _str(w: _Where, value: Any, where: str) -> str:
    if not isinstance(value, str) or not value:
        raise w.fail(where, f"expected a non-empty string, got {value!r}")
    return value


def _number(w: _Where, value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise w.fail(where, f"expected a number, got {value!r}")
    if not 1e-6 <= value <= 1e6:
        raise w.fail(where, f"expected a number in [1e-06, 1e+06] (seconds), got {value!r}")
    return float(value)


def _param(w: _Where, value: Any, where: str) -> Any:
    """A benchmark parameter: a number, string or boolean, or a list of them (as a tuple)."""
    if isinstance(value, list):
        return tuple(_param(w, v, f"{where}[{j}]") for j, v in enumerate(value))
    if isinstance(value, bool | int | str) or (isinstance(value, float) and math.isfinite(value)):
        return value
    raise w.fail(where, f"expected a number, string, boolean or list of them, got {value!r}")


def _readable(w: _Where, field: str, path: Path, read: Any) -> None:
    """Read an instance file once now, so that a broken one stops the sweep before any run.

    The error names the sweep file, the field and the instance file's own
    error (which carries the instance file and, for syntax, ``line:col``).
    """
    try:
        read(path)
    except MultiarmError as exc:
        shown = str(exc)
        if fspath(path) not in shown and path.name not in shown:
            shown = f"{fspath(path)}: {shown}"
        raise w.fail(field, f"instance file is broken: {shown}") from None
