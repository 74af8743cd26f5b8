"""Distance transforms on occupancy grids (Jarvis), and the any-angle
"modified distance transform" (MDT) of the thesis.

The transform is rooted at the goal: every free cell gets its distance to the
goal, so one field serves any number of starts (:func:`distance_field`), and a
path is the steepest descent on it (:func:`path_from_field`).

Registered planners (family ``"grid"``):

* ``dt`` - the thesis' 3:4 chamfer transform (side step 3, diagonal 4; the
  field is reported in cells, value / 3). By default a diagonal step may pass
  one blocked corner, as in the thesis' worked example (Fig. 2.4, built in as
  map ``fig2.4``); ``DTParams(corner_cutting=False)`` forbids it.
* ``dt-octile`` - exact 8-connected distances, 1 and sqrt(2), no corner
  cutting: the MovingAI benchmark metric.
* ``mdt`` - the modified distance transform: the Euclidean length of the
  shortest chain of collision-free straight segments between free cell
  centres. ``MDTParams(fill="exact")`` (default) is Dijkstra on the
  line-of-sight graph; ``fill="levels"`` is the thesis' own procedure
  (section 2.2.4: level 1 = cells that see the goal, level k + 1 = cells that
  see a level-k cell, never revisited), which can be longer. By default it
  takes the ``dt``'s corner rule, the thesis' (a segment may touch a blocked
  cell at a corner); ``MDTParams(corner_cutting=False)`` forbids it.

Two corner rules (the transforms name theirs in ``info["corner_cutting"]``): the
thesis' (``dt`` and ``mdt`` by default: a move may touch a blocked cell at a corner
but enter no blocked cell) and the closed-square rule of MovingAI (``dt-octile``,
the two with ``corner_cutting=False``, and the GA, VFF and VFH planners: a move
touches no blocked square at all); see :mod:`._kernels`. No move ever passes
between two blocked cells that touch at a corner. Under one rule every
8-connected path is also an any-angle path, so the exact MDT is never longer
than a transform of the same rule (and the thesis-rule MDT never longer than any
of them).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_int
from subtask_opt.base.results import Outcome, PlanResult
from subtask_opt.planners.base import register
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid.world import GridWorld, check_small_grid

METRICS = ("chamfer34", "octile", "anyangle")
"""Metrics of :func:`distance_field`."""
DT_METRICS = ("chamfer34", "octile")
"""Metrics of :class:`DTParams` (the 8-connected transforms)."""
FILLS = ("exact", "levels")
"""Fills of :class:`MDTParams`."""
_EMPTY_TARGETS = np.zeros(0, dtype=np.int64)


@dataclass(frozen=True)
class DTParams:
    """Options of the 8-connected transforms (planners ``dt`` and ``dt-octile``).

    Attributes:
        metric: ``"chamfer34"`` (thesis DT, 3:4) or ``"octile"`` (exact 1 : sqrt 2).
        corner_cutting: whether a diagonal step may pass one blocked side
            cell; ``None`` picks the metric's convention: True for
            ``chamfer34`` (the thesis' Fig. 2.4), False for ``octile`` (MovingAI).
    """

    metric: str = "chamfer34"
    corner_cutting: bool | None = None

    def __post_init__(self) -> None:
        if self.metric not in DT_METRICS:
            raise ParameterError(
                f"DTParams.metric must be one of {', '.join(DT_METRICS)}, got {self.metric!r}")
        if self.corner_cutting is not None and not isinstance(self.corner_cutting, bool):
            raise ParameterError(f"DTParams.corner_cutting must be True, False or None, "
                                 f"got {self.corner_cutting!r}")

    @property
    def cuts_corners(self) -> bool:
        """The effective corner-cutting rule."""
        if self.corner_cutting is None:
            return self.metric == "chamfer34"
        return self.corner_cutting


@dataclass(frozen=True)
class MDTParams:
    """Options of the modified distance transform (planner ``mdt``).

    Attributes:
        fill: ``"exact"`` (Dijkstra on the line-of-sight graph) or
            ``"levels"`` (the thesis' level-by-level fill).
        max_free_cells: both fills test pairs of free cells for line of sight
            (O(n^2) tests); grids with more free cells are refused rather than
            left running for hours.
        corner_cutting: True (default, the thesis' rule, as the ``dt``'s): a
            segment may touch a blocked cell at a corner, never pass between two
            blocked cells touching there; False: it touches no blocked square
            (the closed-square rule of ``dt-octile`` and MovingAI).
    """

    fill: str = "exact"
    max_free_cells: int = 20000
    corner_cutting: bool = True

    def __post_init__(self) -> None:
        if self.fill not in FILLS:
            raise ParameterError(
                f"MDTParams.fill must be one of {', '.join(FILLS)}, got {self.fill!r}")
        require_int("MDTParams", "max_free_cells", self.max_free_cells, 1)
        if not isinstance(self.corner_cutting, bool):
            raise ParameterError(f"MDTParams.corner_cutting must be True or False, "
                                 f"got {self.corner_cutting!r}")


def _weights(metric: str) -> tuple[float, float, float]:
    """(side, diagonal, scale) for the 8-connected metrics; field = raw / scale."""
    if metric == "chamfer34":
        return 3.0, 4.0, 3.0
    return 1.0, math.sqrt(2.0), 1.0


def _blocked(world: GridWorld) -> np.ndarray:
    return world.occupancy.view(np.uint8)


def _mdt_params(fill: str, corner_cutting: bool | None, max_free_cells: int = 20000
                ) -> MDTParams:
    """Validated any-angle options; ``corner_cutting=None``: the MDT's default."""
    if corner_cutting is None:
        return MDTParams(fill, max_free_cells)
    return MDTParams(fill, max_free_cells, corner_cutting)


def distance_field(world: GridWorld, goal: Any, metric: str = "octile", *,
                   corner_cutting: bool | None = None, fill: str = "exact",
                   stop_at: Any = None, max_free_cells: int = 20000) -> np.ndarray:
    """Distance from every cell to ``goal``, shape (height, width), in cells.

    Blocked and unreachable cells hold ``inf``. ``corner_cutting`` is the
    corner rule (None: the metric's convention, True for ``chamfer34`` and
    ``anyangle``, the thesis' rule; False for ``octile``; see :class:`DTParams`
    and :class:`MDTParams`); ``fill`` and ``max_free_cells`` apply to
    ``"anyangle"``.
    ``stop_at`` (an iterable of cells (x, y), 8-connected metrics only) ends
    the transform as soon as those cells are final, which is what a single
    query needs; cells not yet final then hold ``inf``.

    Raises:
        UnreachableError: ``goal`` (or a ``stop_at`` cell) outside the grid or blocked.
        ParameterError: unknown ``metric``, or an any-angle grid over ``max_free_cells``.
    """
    if metric not in METRICS:
        raise ParameterError(f"distance_field: metric must be one of {', '.join(METRICS)}, "
                             f"got {metric!r}")
    gx, gy = world.check_cell("goal", goal)
    blocked = _blocked(world)
    if metric == "anyangle":
        cut = _mdt_params(fill, corner_cutting, max_free_cells).corner_cutting
        if stop_at is not None:
            raise ParameterError("distance_field: stop_at is only for the 8-connected metrics")
        check_small_grid(world, max_free_cells, "the any-angle transform checks every pair "
                                                "of free cells")
        if fill == "levels":
            return K.visibility_levels(blocked, gx, gy, cut)
        return K.visibility_field(blocked, gx, gy, cut)
    cut = DTParams(metric, corner_cutting).cuts_corners
    targets = _EMPTY_TARGETS
    if stop_at is not None:
        cells = [world.check_cell("stop_at cell", c) for c in stop_at]
        targets = np.array([y * world.width + x for x, y in cells], dtype=np.int64)
        if targets.size == 0:
            # an empty request means "nothing is needed", not "the whole field"
            return np.full(world.occupancy.shape, np.inf)
    side, diag, scale = _weights(metric)
    field = K.chamfer_field(blocked, gx, gy, side, diag, cut, targets)
    if scale != 1.0:
        field /= scale
    return field


def path_from_field(world: GridWorld, field: np.ndarray, start: Any,
                    metric: str = "octile", *, corner_cutting: bool | None = None,
                    fill: str = "exact") -> np.ndarray:
    """Steepest-descent path from ``start`` down ``field`` to its zero cell.

    8-connected metrics: to the neighbour the value came from. ``anyangle``:
    ``fill="exact"`` jumps to the visible cell that realises the value (the
    path has the field's length); ``fill="levels"`` follows the thesis' step 5
    (jump to the visible cell of least value). ``corner_cutting`` must be the
    field's (as for :func:`distance_field`). Returns a (k, 2) int array of
    cells (x, y), start first; empty when the start cannot reach the goal.
    """
    if metric not in METRICS:
        raise ParameterError(f"path_from_field: metric must be one of {', '.join(METRICS)}, "
                             f"got {metric!r}")
    sx, sy = world.check_cell("start", start)
    field = np.asarray(field, dtype=np.float64)
    if field.shape != world.occupancy.shape:
        raise ParameterError(
            f"field shape {field.shape} does not match the grid {world.occupancy.shape}")
    blocked = _blocked(world)
    if metric == "anyangle":
        cut = _mdt_params(fill, corner_cutting).corner_cutting
        if fill == "levels":
            return K.descend_least_visible(blocked, field, sx, sy, cut)
        return K.visibility_descend(blocked, field, sx, sy, cut)
    cut = DTParams(metric, corner_cutting).cuts_corners
    side, diag, scale = _weights(metric)
    return K.descend(blocked, field * scale, sx, sy, side, diag, cut)


def _no_seed_no_stop(name: str, seed: object, stop: object) -> None:
    if seed is not None:
        raise ParameterError(f"{name} is deterministic: seed must be None, got {seed!r}")
    if stop is not None:
        raise ParameterError(f"{name} is not iterative: stop must be None, got {stop!r}")


def _field_plan(world: GridWorld, start: Any, goal: Any, name: str, metric: str,
                info: dict[str, Any], **field_options: Any) -> PlanResult:
    start_xy = world.check_cell("start", start)
    goal_xy = world.check_cell("goal", goal)
    t0 = time.perf_counter()
    field = distance_field(world, goal_xy, metric, **field_options)
    options = {k: v for k, v in field_options.items() if k in ("corner_cutting", "fill")}
    path = path_from_field(world, field, start_xy, metric, **options)
    runtime = time.perf_counter() - t0
    value = float(field[start_xy[1], start_xy[0]])
    info = {"metric": metric, **info, "field_value": value if math.isfinite(value) else None}
    if path.shape[0] == 0:
        return PlanResult(np.zeros((0, 2)), False,
                          f"no path: goal {goal_xy} is not reachable from start {start_xy}",
                          name, runtime, info=info, outcome=Outcome.NO_PATH)
    message = "ok: start is the goal" if start_xy == goal_xy else "ok"
    return PlanResult(path.astype(float), True, message, name, runtime, info=info)


def plan(world: GridWorld, start: Any, goal: Any, *, params: DTParams | None = None,
         seed: int | None = None, stop: Any = None) -> PlanResult:
    """Plan with an 8-connected distance transform (default: the thesis' 3:4 chamfer).

    Deterministic: ``seed`` and ``stop`` must be None. Returns a
    :class:`PlanResult` with the cell path (``planner`` is ``"dt"`` for the
    chamfer, ``"dt-octile"`` for the octile metric); ``success=False`` with
    outcome ``no_path`` when the goal cannot be reached; start == goal gives
    a one-cell path of length 0. ``info`` holds ``metric``,
    ``corner_cutting`` and ``field_value`` (the value at the start, in cells).

    Raises:
        UnreachableError: start or goal outside the grid or blocked.
        ParameterError: a seed or a stopping criterion was given.
    """
    params = params or DTParams()
    name = "dt" if params.metric == "chamfer34" else "dt-octile"
    _no_seed_no_stop(name, seed, stop)
    cut = params.cuts_corners
    return _field_plan(world, start, goal, name, params.metric, {"corner_cutting": cut},
                       corner_cutting=cut)


@register("grid", "dt", description="distance transform, 3:4 chamfer (thesis; corner cutting)")
def plan_dt(world: GridWorld, start: Any, goal: Any, *, params: DTParams | None = None,
            seed: int | None = None, stop: Any = None) -> PlanResult:
    """The thesis' 3:4 distance transform: :func:`plan` with ``DTParams("chamfer34")``."""
    return _plan_metric("dt", "chamfer34", "dt-octile", world, start, goal, params, seed, stop)


@register("grid", "dt-octile",
          description="distance transform, exact octile 1:sqrt2, no corner cutting (MovingAI)")
def plan_octile(world: GridWorld, start: Any, goal: Any, *, params: DTParams | None = None,
                seed: int | None = None, stop: Any = None) -> PlanResult:
    """The exact 8-connected transform: :func:`plan` with ``DTParams("octile")``."""
    return _plan_metric("dt-octile", "octile", "dt", world, start, goal, params, seed, stop)


def _plan_metric(name: str, metric: str, other: str, world: GridWorld, start: Any, goal: Any,
                 params: DTParams | None, seed: int | None, stop: Any) -> PlanResult:
    """:func:`plan` for planner ``name``, whose params must have ``metric``
    (the error points to planner ``other`` otherwise)."""
    params = params or DTParams(metric)
    if params.metric != metric:
        raise ParameterError(f"planner {name} takes DTParams(metric={metric!r}), "
                             f"got metric={params.metric!r} (use {other})")
    return plan(world, start, goal, params=params, seed=seed, stop=stop)


@register("grid", "mdt", description="modified (any-angle) distance transform, exact or "
                                    "levels (thesis; corner cutting)")
def plan_mdt(world: GridWorld, start: Any, goal: Any, *, params: MDTParams | None = None,
             seed: int | None = None, stop: Any = None) -> PlanResult:
    """The modified distance transform (see :class:`MDTParams`); deterministic.

    ``info`` holds ``metric`` (``"anyangle"``), ``fill``, ``corner_cutting`` and
    ``field_value`` (the field at the start; for ``fill="exact"`` it equals the path
    length).

    Raises:
        UnreachableError: start or goal outside the grid or blocked.
        ParameterError: a seed or stopping criterion, or a grid over ``max_free_cells``.
    """
    params = params or MDTParams()
    _no_seed_no_stop("mdt", seed, stop)
    return _field_plan(world, start, goal, "mdt", "anyangle",
                       {"fill": params.fill, "corner_cutting": params.corner_cutting},
                       fill=params.fill, max_free_cells=params.max_free_cells,
                       corner_cutting=params.corner_cutting)
