"""Mobile-robot planners of the same research line, one folder per family.

* :mod:`.grid` - occupancy grids: distance transforms (3/4 chamfer, octile),
  any-angle MDT, the GA path planner on the shared GA core, VFF, VFH.
* :mod:`.polygon` - polygon worlds: MAKLINK + Dijkstra / improved Dijkstra, PSO,
  the exact visibility graph.
* :mod:`.reactive` - a unicycle with a sonar ring: fuzzy via-point selection,
  sonar VFF and VFH.
* :mod:`.agv` - an AGV among moving obstacles: certainty grid, 2-bit local map,
  quadtree, t-second collision check.

:mod:`.base` holds the planner protocol, the registry and the shared outcomes.
"""
