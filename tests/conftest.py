"""Shared test fixtures: a headless matplotlib, the shared benchmark data, reduced sizes.

Reduced sizes: ``make coverage`` runs the kernels as plain Python
(``NUMBA_DISABLE_JIT=1``), which is 10 to 1000 times slower than compiled. Then
:data:`REDUCED` is true and the slowest tests run smaller instances through
:func:`size` and fewer Hypothesis examples through :func:`examples`; the lines
they cover are the same, and ``make test`` (compiled kernels) keeps the full
sizes.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TypeVar

import pytest

from subtask_opt import _kernel_cache

os.environ.setdefault("MPLBACKEND", "Agg")

pytest_plugins = ["tests.fuzz_report"]  # counts a fuzz run's inputs when FUZZ_REPORT is set

PROJECT_ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = PROJECT_ROOT.parent / "shared" / "data"

# numba's once-per-process "compiling ..." notice (tests/test_kernel_cache.py tests it) goes
# to stderr only while the cache is cold: keep it out of the other tests' stderr checks.
_kernel_cache._announced = True

REDUCED = os.environ.get("NUMBA_DISABLE_JIT", "0").strip() not in ("", "0")
"""True when the kernels run as plain Python (the coverage run): use the reduced sizes."""

_T = TypeVar("_T")


def size(normal: _T, reduced: _T) -> _T:
    """``normal`` in the ordinary test run, ``reduced`` when the kernels run as Python."""
    return reduced if REDUCED else normal


def examples(normal: int, reduced: int | None = None) -> int:
    """Hypothesis ``max_examples``: ``normal``, or ``reduced`` (default a fifth, at least 3)
    when the kernels run as Python."""
    if not REDUCED:
        return normal
    return reduced if reduced is not None else max(3, normal // 5)


@pytest.fixture(scope="session")
def movingai_dir() -> Path:
    """The MovingAI maps and scenarios in ../shared/data/movingai (see README)."""
    path = SHARED_DATA / "movingai"
    if not path.is_dir():
        pytest.skip(f"shared benchmark data not found at {path}")
    return path


@pytest.fixture(scope="module")
def seed003():
    """The MAKLINK paper's 350 x 350 world with its six obstacles (convex hulls)."""
    from subtask_opt.planners.polygon.world import PolygonWorld

    return PolygonWorld.builtin("seed003")


# Several world strategies draw free points by rejection (obstacles can cover much of a small
# world), so some seeds filter out more inputs than hypothesis' health check allows; the inputs
# that are kept are still valid worlds, and a health-check failure would make CI depend on the
# random seed.
from hypothesis import HealthCheck, settings  # noqa: E402

settings.register_profile("subtask_opt", suppress_health_check=[HealthCheck.filter_too_much])
settings.load_profile("subtask_opt")
