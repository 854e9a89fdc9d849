"""Measurement functions for the tests of ``benchmark`` sweeps (imported by name)."""

from __future__ import annotations

from typing import Any

import numpy as np


def table(seed: int, n: int, scale: float = 1.0) -> list[dict[str, Any]]:
    """``n`` rows of seeded numbers (deterministic: the same seed, the same rows)."""
    x = np.random.default_rng(seed).random(n) * scale
    return [{"i": i, "x": x[i], "size": [n, i]} for i in range(n)]


def one(seed: int, label: str) -> dict[str, Any]:
    """One row."""
    return {"label": label, "seed_seen": seed, "flag": True}


def fails(seed: int) -> dict[str, Any]:
    """Raises (the sweep records it and goes on)."""
    raise RuntimeError(f"measurement {seed} broke")


def wrong(seed: int) -> int:
    """Returns what is not a row."""
    return seed


def unplain(seed: int) -> dict[str, Any]:
    """A row holding an object that is not plain data."""
    return {"thing": object()}


NOT_CALLABLE = 3
