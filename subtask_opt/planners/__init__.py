"""Mobile-robot planners of the same research line, one module each.

Every planner module has ``plan(world, start, goal, *, params=..., seed=...) ->
PlanResult`` (:class:`subtask_opt.result.PlanResult`); simulations return a
run record. Worlds:

* :class:`GridWorld` (:mod:`.grid`) - occupancy grids from ASCII, arrays, PNG
  images and MovingAI maps; planners :mod:`.distance_transform` (Jarvis 3/4
  chamfer, exact octile, any-angle "modified" transform), :mod:`.ga_path`
  (GA path planner on the shared GA core), :mod:`.vff`, :mod:`.vfh`,
  :mod:`.quadtree`; the AGV simulation :mod:`.agv` with
  :mod:`.certainty_grid` maps from images.
* :class:`PolygonWorld` (:mod:`.world`) - polygon obstacles; planners
  :mod:`.visibility` (exact shortest path), :mod:`.maklink` (MAKLINK graph +
  Dijkstra / improved Dijkstra), :mod:`.pso`; the reactive navigation
  simulation :mod:`.reactive_sim` (fuzzy via-point selection, VFF, VFH).
"""

from .grid import GridWorld
from .world import PolygonWorld

__all__ = ["GridWorld", "PolygonWorld"]
