"""Vector field histogram (Borenstein & Koren 1991) as a local grid planner.

Each step the cells of the active window (a certainty grid filled by a
simulated sensor) vote into a polar histogram of ``n = 360 / alpha`` sectors
with magnitude ``m = C^2 (a - b d)`` (eq. 2.7-2.10); the histogram is smoothed
with weights 1..l+1..1 (eq. 2.11). Sectors below ``threshold`` form valleys;
the robot steers at the target if its sector lies in a wide valley, else at
the middle of the nearest valley (up to ``s_max`` sectors wide). Runs end as
for :mod:`subtask_opt.planners.grid.vff`: goal, collision, stall or step limit.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_int, require_positive
from subtask_opt.base.results import PlanResult
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid.vff import RobotParams, _result
from subtask_opt.planners.grid.world import GridWorld


@dataclass(frozen=True)
class VFHParams:
    """VFH histogram and steering parameters (eq. 2.7-2.11) and the robot.

    Attributes:
        alpha_deg: sector width alpha; ``360 / alpha_deg`` must be a whole number.
        a, b: magnitude ``m = C^2 (a - b d)``; ``b = None`` picks
            ``a / (window * sqrt(2))`` so that ``m`` falls to 0 at the window corner.
        smoothing: ``l`` of eq. 2.11.
        threshold: smoothed density below which a sector is free.
        s_max: sectors of a wide valley.
        robot: the simulated robot (:class:`RobotParams`; slower than VFF's by
            default, 0.1 cell per step, which keeps VFH out of collisions in tight maps).
    """

    alpha_deg: float = 10.0
    a: float = 1.0
    b: float | None = None
    smoothing: int = 2
    threshold: float = 10.0
    s_max: int = 8
    robot: RobotParams = RobotParams(speed=0.1)

    def __post_init__(self) -> None:
        o = "VFHParams"
        require_positive(o, "alpha_deg", self.alpha_deg)
        n = 360.0 / self.alpha_deg
        if abs(n - round(n)) > 1e-9 or round(n) < 4:
            raise ParameterError(
                f"{o}.alpha_deg must divide 360 into at least 4 sectors, got {self.alpha_deg!r}")
        require_positive(o, "a", self.a)
        if self.b is not None:
            require_positive(o, "b", self.b)
        require_int(o, "smoothing", self.smoothing, 0)
        require_positive(o, "threshold", self.threshold)
        require_int(o, "s_max", self.s_max, 1)

    @property
    def b_value(self) -> float:
        return self.b if self.b is not None else self.a / (self.robot.window * math.sqrt(2.0))


def plan(world: GridWorld, start: Any, goal: Any, *, params: VFHParams | None = None,
         seed: int | None = None) -> PlanResult:
    """Drive from ``start`` to ``goal`` with the vector field histogram.

    Deterministic (``seed`` is accepted for a uniform interface). See
    :func:`subtask_opt.planners.grid.vff.plan` for the result.

    Raises:
        UnreachableError: start or goal outside the grid or blocked.
    """
    params = params or VFHParams()
    r = params.robot
    s = world.check_cell("start", start)
    g = world.check_cell("goal", goal)
    p = np.array([r.window, math.radians(params.alpha_deg), params.a, params.b_value,
                  params.smoothing, params.threshold, params.s_max,
                  math.radians(r.max_turn_deg), r.speed, r.max_steps, r.goal_tolerance,
                  r.stall_steps, r.stall_gain, r.certainty_increment, r.certainty_max])
    t0 = time.perf_counter()
    code, traj = K.vfh_run(world.occupancy.view(np.uint8), float(s[0]), float(s[1]),
                           float(g[0]), float(g[1]), p)
    return _result(world, int(code), traj, "vfh", time.perf_counter() - t0, g)
