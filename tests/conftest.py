"""The test contract: shared fixtures and the Hypothesis profiles.

Hypothesis runs derandomized by default (profile ``ci``) so that the suite is
deterministic; ``pytest --hypothesis-profile=explore`` searches with fresh
randomness and more examples.
"""

from __future__ import annotations

import os

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
