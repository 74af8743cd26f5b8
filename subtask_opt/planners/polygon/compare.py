"""One planner run set against the exact optimum (what ``plan polygon`` prints).

:func:`plan_against_optimum` runs any registered polygon planner and the
visibility-graph optimum for the same start and goal, so the caller gets the
gap without doing geometry itself.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.results import PlanResult
from subtask_opt.base.stop import Progress
from subtask_opt.planners.base import get_planner
from subtask_opt.planners.polygon import maklink, visibility
from subtask_opt.planners.polygon.world import PolygonWorld


@dataclass(frozen=True)
class PlannerRun:
    """A plan, the exact optimum for the same points, and the MAKLINK graph if one was used.

    Attributes:
        world: the world planned in.
        start, goal: the checked end points.
        result: the planner's answer.
        optimum: exact shortest length (inf when no path exists).
        graph: the MAKLINK graph for MAKLINK-based planners, else None.
    """

    world: PolygonWorld
    start: np.ndarray
    goal: np.ndarray
    result: PlanResult
    optimum: float
    graph: maklink.MaklinkGraph | None

    @property
    def gap_pct(self) -> float | None:
        """How much longer than the optimum the path is, in percent (None without a path)."""
        if not self.result.success or not math.isfinite(self.optimum):
            return None
        if self.optimum == 0.0:
            return 0.0
        return 100.0 * (self.result.length / self.optimum - 1.0)

    def report_lines(self) -> list[str]:
        """The intermediate lengths and the gap to the optimum, one fact per line."""
        info = self.result.info
        lines = []
        if "dijkstra_length" in info and self.result.success:
            text = f"Dijkstra {info['dijkstra_length']:.4f}"
            if "improved_length" in info:
                text += f", improved {info['improved_length']:.4f}"
            lines.append(text)
        gap = self.gap_pct
        if gap is not None:
            lines.append(f"exact optimum {self.optimum:.4f} (gap {max(gap, 0.0):.3f} %)")
        elif not math.isfinite(self.optimum):
            lines.append("exact optimum: no collision-free path exists")
        return lines

    def to_dict(self) -> dict[str, Any]:
        """JSON form: the result's fields plus world, start, goal, optimum and gap."""
        out = self.result.to_dict()
        out.update(world=self.world.name, start=self.start.tolist(), goal=self.goal.tolist(),
                   optimum=self.optimum if math.isfinite(self.optimum) else None,
                   gap_pct=self.gap_pct)
        return out


def plan_against_optimum(world: PolygonWorld, planner: str, start: Any, goal: Any, *,
                         params: Any = None, seed: int | None = None, stop: Any = None,
                         on_chunk: Callable[[Progress], None] | None = None) -> PlannerRun:
    """Run registered polygon planner ``planner`` and the exact optimum.

    ``params``, ``seed``, ``stop`` and ``on_chunk`` reach the planner only when
    it is stochastic / iterative (the registry says which); deterministic
    planners run with none of them.

    Raises:
        ParameterError: unknown planner name (the message lists the choices).
        InputDataError, UnreachableError: bad start or goal.
    """
    info = get_planner("polygon", planner)
    s = world.check_point("start", start)
    g = world.check_point("goal", goal)
    kwargs: dict[str, Any] = {}
    if info.stochastic:
        kwargs["seed"] = seed
    if info.iterative:
        kwargs.update(params=params, stop=stop)
        if on_chunk is not None:
            kwargs["on_chunk"] = on_chunk
    result = info.plan(world, s, g, **kwargs)
    optimum = (result.length if planner == "visibility" and result.success
               else visibility.shortest_path_length(world, s, g))
    graph = maklink.graph_for(world) if planner != "visibility" else None
    return PlannerRun(world=world, start=s, goal=g, result=result, optimum=optimum, graph=graph)
