"""Polygon worlds: MAKLINK graph + Dijkstra, improved Dijkstra, PSO, exact visibility graph."""

from subtask_opt.planners.polygon.world import PolygonWorld

__all__ = ["PolygonWorld"]
