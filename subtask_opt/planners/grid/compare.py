"""All grid planners behind one name, and the thesis' per-map comparison table.

:data:`PLANNERS` maps a planner name (as the CLI spells it) to its ``plan``
function; :func:`compare` runs each on one map and returns table rows like the
thesis' Tables 4.2-4.7 (time, length in cells, turns).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

from subtask_opt.base.errors import ParameterError
from subtask_opt.base.results import PlanResult
from subtask_opt.planners.grid import distance_transform as dt
from subtask_opt.planners.grid import ga_path, vff, vfh
from subtask_opt.planners.grid.world import GridWorld

PLANNERS: dict[str, Callable[..., PlanResult]] = {
    "dt": partial(dt.plan, params=dt.DTParams("chamfer34")),
    "dt-octile": partial(dt.plan, params=dt.DTParams("octile")),
    "mdt": partial(dt.plan, params=dt.DTParams("anyangle")),
    "ga": partial(ga_path.plan, params=ga_path.GAPathParams()),
    "ga-paper": partial(ga_path.plan, params=ga_path.GAPathParams.paper()),
    "vff": vff.plan,
    "vfh": vfh.plan,
}
#: The planners of the comparison table, in table order.
TABLE_PLANNERS: tuple[str, ...] = ("dt", "mdt", "ga", "ga-paper", "vff", "vfh")


def plan_grid(world: GridWorld, start: Any, goal: Any, planner: str, *,
              seed: int = 0) -> PlanResult:
    """Run the planner called ``planner`` (a key of :data:`PLANNERS`).

    Raises:
        ParameterError: unknown planner name.
        UnreachableError: start or goal outside the grid or blocked.
    """
    if planner not in PLANNERS:
        raise ParameterError(
            f"unknown planner {planner!r}; choose one of {', '.join(PLANNERS)}")
    return PLANNERS[planner](world, start, goal, seed=seed)


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

    def to_dict(self) -> dict[str, Any]:
        return {"map": self.map, "planner": self.planner, "success": self.success,
                "time_s": self.time_s, "length": self.length if self.success else None,
                "turns": self.turns, "message": self.message}


def compare(world: GridWorld, start: Any, goal: Any, *,
            planners: tuple[str, ...] = TABLE_PLANNERS, seed: int = 0,
            repeats: int = 3) -> list[CompareRow]:
    """Run each planner on one map after a warm-up call (JIT compile kept out
    of the times); a row's time is the best of ``repeats`` runs with the same
    seed (runs of a seed are identical, only the clock varies)."""
    rows = []
    for name in planners:
        plan_grid(world, start, goal, name, seed=seed)  # warm-up
        best = None
        for _ in range(max(1, repeats)):
            t0 = time.perf_counter()
            res = plan_grid(world, start, goal, name, seed=seed)
            elapsed = time.perf_counter() - t0
            if best is None or elapsed < best[0]:
                best = (elapsed, res)
        elapsed, res = best
        rows.append(CompareRow(world.name, name, res.success, elapsed, res.length, res.turns,
                               res.message, res))
    return rows


def format_table(rows: list[CompareRow]) -> str:
    """Rows as a fixed-width text table."""
    lines = [f"{'map':<10} {'planner':<9} {'time':>10} {'length':>8} {'turns':>5}  result",
             "-" * 60]
    for r in rows:
        t = f"{r.time_s * 1e3:.3f} ms"
        length = f"{r.length:.2f}" if r.success else "-"
        turns = str(r.turns) if r.success else "-"
        lines.append(f"{r.map:<10} {r.planner:<9} {t:>10} {length:>8} {turns:>5}  "
                     f"{'ok' if r.success else r.message}")
    return "\n".join(lines)
