"""Distance transforms on occupancy grids (Jarvis), and the any-angle
"modified distance transform" of the thesis.

The transform is rooted at the goal: every free cell gets its distance to the
goal, so one field serves any number of starts (:func:`distance_field`), and a
path is the steepest descent on it (:func:`path_from_field`).

Metrics (``DTParams.metric``):

* ``"chamfer34"`` - the thesis' integer weights, 3 for a side step and 4 for a
  diagonal (3:4 approximates 1:sqrt(2)); the field is reported in cells
  (value / 3).
* ``"octile"`` - exact 8-connected distances, 1 and sqrt(2). This is the
  MovingAI benchmark metric.
* ``"anyangle"`` - the modified distance transform (MDT): the true Euclidean
  length of the shortest chain of collision-free straight segments between
  free cell centres (Dijkstra on the line-of-sight graph).

Both 8-connected metrics forbid corner cutting (a diagonal step needs both
side cells free); a segment is collision-free when it touches no closed
blocked cell, so every 8-connected path is also an any-angle path and the MDT
is never longer than either distance transform.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_int
from subtask_opt.base.results import PlanResult
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid.world import GridWorld

METRICS = ("chamfer34", "octile", "anyangle")
_EMPTY_TARGETS = np.zeros(0, dtype=np.int64)


@dataclass(frozen=True)
class DTParams:
    """Options of :func:`plan`.

    Attributes:
        metric: ``"chamfer34"`` (thesis DT), ``"octile"`` (exact 8-connected)
            or ``"anyangle"`` (the modified distance transform).
        max_free_cells: the any-angle transform checks every pair of free
            cells (O(n^2) line-of-sight tests); grids with more free cells are
            refused rather than left running for hours.
    """

    metric: str = "chamfer34"
    max_free_cells: int = 20000

    def __post_init__(self) -> None:
        if self.metric not in METRICS:
            raise ParameterError(
                f"DTParams.metric must be one of {', '.join(METRICS)}, got {self.metric!r}")
        require_int("DTParams", "max_free_cells", self.max_free_cells, 1)


def _weights(metric: str) -> tuple[float, float, float]:
    """(side, diagonal, scale) for the 8-connected metrics; field = raw / scale."""
    if metric == "chamfer34":
        return 3.0, 4.0, 3.0
    return 1.0, math.sqrt(2.0), 1.0


def _blocked(world: GridWorld) -> np.ndarray:
    return world.occupancy.view(np.uint8)


def distance_field(world: GridWorld, goal: Any, metric: str = "octile", *,
                   stop_at: Any = None, max_free_cells: int = 20000) -> np.ndarray:
    """Distance from every cell to ``goal``, shape (height, width), in cells.

    Blocked and unreachable cells hold ``inf``. ``stop_at`` (an iterable of
    cells (x, y), 8-connected metrics only) ends the transform as soon as those
    cells are final, which is what a single query needs; cells not yet final
    then hold ``inf``. ``max_free_cells`` bounds the any-angle
    transform (see :class:`DTParams`).

    Raises:
        UnreachableError: ``goal`` (or a ``stop_at`` cell) outside the grid or blocked.
        ParameterError: unknown ``metric``, or an any-angle grid over ``max_free_cells``.
    """
    DTParams(metric, max_free_cells)
    gx, gy = world.check_cell("goal", goal)
    blocked = _blocked(world)
    if metric == "anyangle":
        if stop_at is not None:
            raise ParameterError("distance_field: stop_at is only for the 8-connected metrics")
        n_free = int(np.count_nonzero(~world.occupancy))
        if n_free > max_free_cells:
            raise ParameterError(
                f"the any-angle transform checks every pair of free cells; this grid has "
                f"{n_free} free cells, more than max_free_cells={max_free_cells}")
        return K.visibility_field(blocked, gx, gy)
    targets = _EMPTY_TARGETS
    if stop_at is not None:
        cells = [world.check_cell("stop_at cell", c) for c in stop_at]
        targets = np.array([y * world.width + x for x, y in cells], dtype=np.int64)
        if targets.size == 0:
            # an empty request means "nothing is needed", not "the whole field"
            return np.full(world.occupancy.shape, np.inf)
    side, diag, scale = _weights(metric)
    field = K.chamfer_field(blocked, gx, gy, side, diag, targets)
    if scale != 1.0:
        field /= scale
    return field


def path_from_field(world: GridWorld, field: np.ndarray, start: Any,
                    metric: str = "octile") -> np.ndarray:
    """Steepest-descent path from ``start`` down ``field`` to its zero cell.

    Returns a (k, 2) int array of cells (x, y), start first; empty when the
    start cannot reach the goal (``inf`` value).
    """
    DTParams(metric)
    sx, sy = world.check_cell("start", start)
    field = np.asarray(field, dtype=np.float64)
    if field.shape != world.occupancy.shape:
        raise ParameterError(
            f"field shape {field.shape} does not match the grid {world.occupancy.shape}")
    blocked = _blocked(world)
    if metric == "anyangle":
        return K.visibility_descend(blocked, field, sx, sy)
    side, diag, scale = _weights(metric)
    return K.descend(blocked, field * scale, sx, sy, side, diag)


def plan(world: GridWorld, start: Any, goal: Any, *, params: DTParams | None = None,
         seed: int | None = None) -> PlanResult:
    """Plan with a distance transform (``seed`` is accepted for a uniform
    interface; the transform is deterministic).

    Returns a :class:`PlanResult` with the cell path; ``success=False`` with
    the reason when the goal cannot be reached. ``info`` holds ``field_value``
    (the transform's value at the start, in cells) and ``metric``.

    Raises:
        UnreachableError: start or goal outside the grid or blocked.
    """
    params = params or DTParams()
    start_xy = world.check_cell("start", start)
    goal_xy = world.check_cell("goal", goal)
    name = {"chamfer34": "dt", "octile": "dt-octile", "anyangle": "mdt"}[params.metric]
    t0 = time.perf_counter()
    field = distance_field(world, goal_xy, params.metric, max_free_cells=params.max_free_cells)
    path = path_from_field(world, field, start_xy, params.metric)
    runtime = time.perf_counter() - t0
    value = float(field[start_xy[1], start_xy[0]])
    info = {"metric": params.metric, "field_value": value if math.isfinite(value) else None}
    if path.shape[0] == 0:
        return PlanResult(np.zeros((0, 2)), False,
                          f"no path: goal {goal_xy} is not reachable from start {start_xy}",
                          name, runtime, info=info)
    return PlanResult(path.astype(float), True, "ok", name, runtime, info=info)


def plan_mdt(world: GridWorld, start: Any, goal: Any, *, seed: int | None = None) -> PlanResult:
    """The modified (any-angle) distance transform: ``plan`` with ``metric="anyangle"``."""
    return plan(world, start, goal, params=DTParams("anyangle"), seed=seed)

