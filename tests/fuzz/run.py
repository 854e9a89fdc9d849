"""Run one fuzz target under atheris (libFuzzer), in its own process.

Usage (the driver :mod:`tests.fuzz.campaign` builds these command lines)::

    python -m tests.fuzz.run TARGET WORKDIR [libFuzzer flags and corpus folders]

``TARGET`` is a key of :data:`tests.fuzz.targets.TARGETS`, or ``all``: every
target in this one process (:class:`tests.fuzz.targets.Multiplex`), or
``module:function`` (a function ``f(data, workdir)`` of its own, as the
driver's tests use).

``WORKDIR`` is a folder the target writes its input files into. Our
packages (and lark, whose parser the SDL and TDL grammars run in) are
instrumented for coverage; the modules compiled by numba are not (numba
reads their bytecode). libFuzzer ends the process itself (``-runs``,
``-max_total_time``, or the first finding, whose input it writes under
``-artifact_prefix``).

The input of a finding is also kept by this process, not only by libFuzzer:
libFuzzer writes it from its exit or signal handlers, after the Python
interpreter has unwound and begun to shut down, so a process killed on the
way (the kernel's out-of-memory killer, a signal from outside) or one whose
shutdown never reaches libFuzzer's ``atexit`` handler leaves no input. So
each input is first written to ``<prefix>current`` (replaced by the next;
after a kill it is the input that was running; the driver removes it after
a run without a finding), and
an exception escaping the target writes the input to
``<prefix>crash-<sha1 of the input>`` (libFuzzer's own name for it) before
it goes on to atheris; the line ``finding input written to PATH`` tells the
driver.
"""

from __future__ import annotations

import hashlib
import importlib
import sys
from collections.abc import Callable, Mapping
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


def artifact_prefix(flags: list[str]) -> str | None:
    """The value of libFuzzer's ``-artifact_prefix=`` among ``flags`` (the last one)."""
    found = [f.split("=", 1)[1] for f in flags if f.startswith("-artifact_prefix=")]
    return found[-1] if found else None


def save_finding(data: bytes, prefix: str) -> str:
    """Write the input of a finding to ``<prefix>crash-<sha1>`` and return the path."""
    path = f"{prefix}crash-{hashlib.sha1(data).hexdigest()}"
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_bytes(data)
    print(f"finding input written to {path}", file=sys.stderr, flush=True)
    return path


def _target(
    name: str, targets: Mapping[str, Callable[[bytes, Path], None]]
) -> Callable[[bytes, Path], None]:
    if ":" not in name:
        return targets[name]
    module, attr = name.split(":", 1)
    found: Callable[[bytes, Path], None] = getattr(importlib.import_module(module), attr)
    return found


def main(argv: list[str]) -> None:
    name, workdir = argv[1], Path(argv[2])
    root = Path(__file__).resolve().parents[2]
    with atheris.instrument_imports(include=list(PACKAGES), exclude=_numba_modules(root)):
        from tests.fuzz.targets import ALL, TARGETS, Multiplex

        target = Multiplex() if name == ALL else _target(name, TARGETS)
        # import (and so instrument) every module the target reaches; a
        # finding on the empty input is found again by the fuzzer below
        for each in TARGETS if name == ALL else [name]:
            try:
                _target(each, TARGETS)(b"", workdir)
            except Exception as exc:
                print(f"warm-up {each}: {type(exc).__name__}: {exc}", file=sys.stderr)

    prefix = artifact_prefix(argv[3:])
    current = f"{prefix}current" if prefix is not None else None

    def one_input(data: bytes) -> None:
        if current is not None:
            with open(current, "wb") as f:
                f.write(data)
        try:
            target(data, workdir)
        except KeyboardInterrupt:
            raise
        except BaseException:
            if prefix is not None:
                save_finding(data, prefix)
            raise

    atheris.Setup([argv[0], *argv[3:]], one_input)
    atheris.Fuzz()


if __name__ == "__main__":
    main(sys.argv)
