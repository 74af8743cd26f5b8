"""Shared test fixtures: a headless matplotlib and the shared benchmark data."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

pytest_plugins = ["tests.fuzz_report"]  # counts a fuzz run's inputs when FUZZ_REPORT is set

PROJECT_ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = PROJECT_ROOT.parent / "shared" / "data"


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
