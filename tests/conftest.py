"""The test contract: shared fixtures and the Hypothesis profiles.

Hypothesis runs derandomized by default (profile ``ci``) so that the suite is
deterministic; ``pytest --hypothesis-profile=explore`` searches with fresh
randomness and more examples.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci",
    derandomize=True,
    deadline=None,
    max_examples=100,
    suppress_health_check=[HealthCheck.too_slow],
    print_blob=True,
)
settings.register_profile("explore", deadline=None, max_examples=1000)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture(autouse=True, scope="session")
def _ctrl_c_raises() -> Iterator[None]:
    """Ctrl-C means KeyboardInterrupt here, however the test run was started.

    The Ctrl-C tests send SIGINT to their own process (or to a command they
    start) and expect Python's KeyboardInterrupt. A process started in the
    background of a non-interactive shell (``make test &``, ``nohup``)
    inherits SIGINT *ignored*, and Python then installs no handler, so those
    tests failed only because of how the run was launched (13 of them under
    ``signal.SIG_IGN``). The default handler is put back for the session,
    which also gives the commands a test starts the default disposition.
    """
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        yield
        return
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.fixture(scope="session")
def supersigma_tasks():  # type: ignore[no-untyped-def]
    from tasklib import load_example

    return load_example("supersigma")


@pytest.fixture(scope="session")
def scara4_tasks():  # type: ignore[no-untyped-def]
    from tasklib import load_example

    return load_example("scara4")


@pytest.fixture(scope="session")
def cell8_tasks():  # type: ignore[no-untyped-def]
    from tasklib import load_example

    return load_example("cell8")


@pytest.fixture(params=["tree", "greedy", "cpsat"])
def any_solver(request: pytest.FixtureRequest) -> str:
    """Each solver of :func:`scheduler.solve` in turn: a test taking it runs once per solver."""
    return str(request.param)
