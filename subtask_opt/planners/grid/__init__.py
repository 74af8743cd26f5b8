"""Occupancy-grid planners: distance transforms, any-angle MDT, GA path planner, VFF, VFH.

The planners register themselves as family ``"grid"`` (see
:func:`subtask_opt.planners.base.planners`); :func:`.world.read_grid` reads a
map file of any supported format.
"""

from subtask_opt.planners.grid.world import GridWorld, read_grid

__all__ = ["GridWorld", "read_grid"]
