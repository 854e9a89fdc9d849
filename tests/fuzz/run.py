"""Run one fuzz target under atheris (libFuzzer), in its own process.

Usage (the driver :mod:`tests.fuzz.campaign` builds these command lines)::

    python -m tests.fuzz.run TARGET WORKDIR [libFuzzer flags and corpus folders]

``TARGET`` is a key of :data:`tests.fuzz.targets.TARGETS`, or ``all``: every
target in this one process (:class:`tests.fuzz.targets.Multiplex`).

``WORKDIR`` is a folder the target writes its input files into. Our
packages (and lark, whose parser the SDL and TDL grammars run in) are
instrumented for coverage; the modules compiled by numba are not (numba
reads their bytecode). libFuzzer ends the process itself (``-runs``,
``-max_total_time``, or the first finding, whose input it writes under
``-artifact_prefix``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import atheris

PACKAGES = ("multiarm", "tasklib", "zones", "scheduler", "workcell", "lark")


def _numba_modules(root: Path) -> list[str]:
    """Modules of ours that numba compiles (never instrumented)."""
    out = []
    for pkg in PACKAGES[:-1]:
        for path in (root / pkg).rglob("*.py"):
            text = path.read_text(encoding="utf-8")
            if "numba" in text or "njit" in text:
                parts = path.relative_to(root).with_suffix("").parts
                if parts[-1] == "__init__":
                    parts = parts[:-1]
                out.append(".".join(parts))
    return out


def main(argv: list[str]) -> None:
    name, workdir = argv[1], Path(argv[2])
    root = Path(__file__).resolve().parents[2]
    with atheris.instrument_imports(include=list(PACKAGES), exclude=_numba_modules(root)):
        from tests.fuzz.targets import ALL, TARGETS, Multiplex

        target = Multiplex() if name == ALL else TARGETS[name]
        # import (and so instrument) every module the target reaches; a
        # finding on the empty input is found again by the fuzzer below
        for each in TARGETS if name == ALL else [name]:
            try:
                TARGETS[each](b"", workdir)
            except Exception as exc:
                print(f"warm-up {each}: {type(exc).__name__}: {exc}", file=sys.stderr)

    def one_input(data: bytes) -> None:
        target(data, workdir)

    atheris.Setup([argv[0], *argv[3:]], one_input)
    atheris.Fuzz()


if __name__ == "__main__":
    main(sys.argv)
