"""Occupancy-grid planners: distance transforms, any-angle MDT, GA path planner, VFF, VFH."""

from subtask_opt.planners.grid.world import GridWorld

__all__ = ["GridWorld"]
