"""Grid planners by registered name, the thesis' per-map comparison table, and
one planning query with everything the CLI writes.

Planner names, descriptions and flags come from the registry
(``planners("grid")``, see :mod:`subtask_opt.planners.base`); :func:`compare`
runs each on one map and returns table rows like the thesis' Tables 4.2-4.7
(time, length in cells, turns).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import require_int
from subtask_opt.base.results import PlanResult
from subtask_opt.planners.base import get_planner, planners
from subtask_opt.planners.grid import distance_transform as dt
from subtask_opt.planners.grid.world import GridWorld


def planner_names() -> tuple[str, ...]:
    """Every registered grid planner, in registration order."""
    return tuple(planners("grid"))


def plan_grid(world: GridWorld, start: Any, goal: Any, planner: str, *,
              seed: int | None = None, stop: Any = None, params: Any = None) -> PlanResult:
    """Run the registered grid planner ``planner``.

    ``seed`` is passed to stochastic planners only (deterministic ones refuse
    a seed), ``stop`` to iterative ones.

    Raises:
        ParameterError: unknown planner name (the message lists the choices).
        UnreachableError: start or goal outside the grid or blocked.
    """
    info = get_planner("grid", planner)
    return info.plan(world, start, goal, params=params,
                     seed=seed if info.stochastic else None,
                     stop=stop if info.iterative else None)


@dataclass(frozen=True)
class GridPlanReport:
    """One planning query: the result, and for the transforms their field.

    Attributes:
        map: the map's name.
        start, goal: the cells asked for.
        result: the planner's :class:`PlanResult`.
        field: the distance transform's field over the work space (the world
            minus ``border`` cells each side), in the planner's own units
            (``dt``: 3 per side step, 4 per diagonal; ``dt-octile`` and
            ``mdt``: cells); ``None`` for the other planners.
        field_unit: what one unit of ``field`` is.
        seed: the seed given (None for deterministic planners).
    """

    map: str
    start: tuple[int, int]
    goal: tuple[int, int]
    result: PlanResult
    field: np.ndarray | None = None
    field_unit: str = ""
    seed: int | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the result's fields, ``map``, ``start``, ``goal``, ``seed``,
        and ``field`` as rows (blocked and unreachable cells null)."""
        out = self.result.to_dict()
        out.update(map=self.map, start=list(self.start), goal=list(self.goal), seed=self.seed)
        if self.field is not None:
            rows = []
            for row in self.field:
                rows.append([_number(v) for v in row])
            out.update(field=rows, field_unit=self.field_unit)
        return out


def _number(v: float) -> float | int | None:
    if not math.isfinite(v):
        return None
    return int(round(v)) if abs(v - round(v)) < 1e-9 else float(v)


def plan_report(world: GridWorld, start: Any, goal: Any, planner: str, *,
                seed: int | None = None, stop: Any = None, border: int = 0,
                warm_up: bool = True) -> GridPlanReport:
    """Plan once (after a warm-up run, so JIT compilation stays out of
    ``runtime_s``) and collect what ``plan grid`` reports.

    ``border``: blocked cells per side around the work space (built-in maps
    carry one), stripped from the reported field.
    """
    require_int("plan_report", "border", border, 0, min(world.width, world.height) // 2)
    s = world.check_cell("start", start)
    g = world.check_cell("goal", goal)
    if warm_up:
        plan_grid(world, s, g, planner, seed=seed, stop=stop)
    result = plan_grid(world, s, g, planner, seed=seed, stop=stop)
    fld: np.ndarray | None = None
    unit = ""
    if planner in ("dt", "dt-octile"):
        metric = "chamfer34" if planner == "dt" else "octile"
        fld = dt.distance_field(world, g, metric)
        if planner == "dt":
            fld, unit = fld * 3.0, "chamfer steps: 3 per side step, 4 per diagonal"
        else:
            unit = "cells (octile)"
    elif planner == "mdt":
        fld, unit = dt.distance_field(world, g, "anyangle"), "cells (any-angle)"
    if fld is not None and border:
        fld = fld[border:-border, border:-border]
    used_seed = seed if get_planner("grid", planner).stochastic else None
    return GridPlanReport(world.name, s, g, result, fld, unit, used_seed)


@dataclass(frozen=True)
class CompareRow:
    """One line of a comparison table."""

    map: str
    planner: str
    success: bool
    time_s: float
    length: float
    turns: int
    message: str
    result: PlanResult

    @property
    def corner_cutting(self) -> bool:
        """The row's corner rule: True for the thesis' (a move may touch a blocked
        corner: ``dt`` and ``mdt`` by default), False for closed squares (the others)."""
        return bool(self.result.info.get("corner_cutting", False))

    def to_dict(self) -> dict[str, Any]:
        return {"map": self.map, "planner": self.planner, "success": self.success,
                "outcome": str(self.result.outcome), "time_s": self.time_s,
                "length": self.length if self.success else None,
                "turns": self.turns, "corner_cutting": self.corner_cutting,
                "message": self.message}


def compare(world: GridWorld, start: Any, goal: Any, *,
            names: tuple[str, ...] | None = None, seed: int | None = None,
            repeats: int = 3, params: dict[str, Any] | None = None) -> list[CompareRow]:
    """Run each planner (``names``; None: every registered grid planner) on one
    map after a warm-up call (JIT compile kept out of the times); a row's time
    is the best of ``repeats`` runs with the same seed (runs of a seed are
    identical, only the clock varies). ``params`` maps a planner name to its
    parameters (the others run with their defaults)."""
    require_int("compare", "repeats", repeats, 1, 10_000)
    params = params or {}
    rows = []
    for name in names if names is not None else planner_names():
        options = params.get(name)
        plan_grid(world, start, goal, name, seed=seed, params=options)  # warm-up
        best: tuple[float, PlanResult] | None = None
        for _ in range(repeats):
            t0 = time.perf_counter()
            res = plan_grid(world, start, goal, name, seed=seed, params=options)
            elapsed = time.perf_counter() - t0
            if best is None or elapsed < best[0]:
                best = (elapsed, res)
        assert best is not None
        elapsed, res = best
        rows.append(CompareRow(world.name, name, res.success, elapsed, res.length, res.turns,
                               res.message, res))
    return rows


def format_table(rows: list[CompareRow]) -> str:
    """Rows as a fixed-width text table; ``corners`` is the row's corner rule (``touch``:
    the thesis', a move may touch a blocked corner; ``closed``: it touches no blocked cell)."""
    lines = [f"{'map':<10} {'planner':<9} {'time':>10} {'length':>8} {'turns':>5} "
             f"{'corners':<7}  result", "-" * 68]
    for r in rows:
        t = f"{r.time_s * 1e3:.3f} ms"
        length = f"{r.length:.2f}" if r.success else "-"
        turns = str(r.turns) if r.success else "-"
        corners = "touch" if r.corner_cutting else "closed"
        lines.append(f"{r.map:<10} {r.planner:<9} {t:>10} {length:>8} {turns:>5} "
                     f"{corners:<7}  {'ok' if r.success else r.message}")
    return "\n".join(lines)
