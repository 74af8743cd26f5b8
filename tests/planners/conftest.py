"""Fixtures shared by the planner tests."""

from __future__ import annotations

import pytest

from subtask_opt.planners.world import PolygonWorld


@pytest.fixture(scope="module")
def seed003() -> PolygonWorld:
    """The MAKLINK paper's 350 x 350 world with its six obstacles (convex hulls)."""
    return PolygonWorld.builtin("seed003")
