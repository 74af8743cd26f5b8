"""Virtual force field (Borenstein & Koren 1989) as a local grid planner.

A simulated point robot drives through the grid, sensing the blocked cells
within a window into a certainty grid C. Every certain cell in the window
pushes it away with ``Fcr C / d^2`` (eq. 2.1-2.2), the target pulls with
``Fct`` (eq. 2.3); the robot steers towards the resultant at rate
``Ks (delta - theta)`` (eq. 2.4-2.6), limited to ``max_turn_deg`` per step.
Every run ends: at the goal, in a collision, in a detected stall (local
minimum or oscillation: no progress towards the goal for ``stall_steps``), or
at the step limit. A failure is a ``success=False`` :class:`PlanResult` with
the reason, and the trajectory driven so far in ``info["trajectory"]``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import require_int, require_positive
from subtask_opt.base.results import PlanResult
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid.world import GridWorld

OUTCOMES = {
    K.REACHED: "ok",
    K.COLLISION: "collision",
    K.LOCAL_MINIMUM: "stall: local minimum (no progress towards the goal)",
    K.OSCILLATION: "stall: oscillation (moving without progress towards the goal)",
    K.STEP_LIMIT: "stall: step limit reached",
    K.NO_VALLEY: "stall: no free direction",
}


@dataclass(frozen=True)
class RobotParams:
    """The simulated robot and its run limits, shared by VFF and VFH.

    Attributes:
        window: sensor / active-window radius, in cells.
        speed: distance per step, in cells.
        max_turn_deg: largest heading change per step.
        max_steps: step limit of a run.
        goal_tolerance: distance to the goal centre that counts as arrived.
        stall_steps: steps without ``stall_gain`` cells of progress that make a stall.
        stall_gain: progress towards the goal that resets the stall counter.
        certainty_increment: certainty added to a sensed blocked cell per step.
        certainty_max: cap of the certainty values.
    """

    window: float = 3.0
    speed: float = 0.2
    max_turn_deg: float = 30.0
    max_steps: int = 2000
    goal_tolerance: float = 0.5
    stall_steps: int = 80
    stall_gain: float = 0.5
    certainty_increment: float = 3.0
    certainty_max: float = 15.0

    def __post_init__(self) -> None:
        o = "RobotParams"
        for name in ("window", "speed", "max_turn_deg", "goal_tolerance", "stall_gain",
                     "certainty_increment", "certainty_max"):
            require_positive(o, name, getattr(self, name))
        require_int(o, "max_steps", self.max_steps, 1)
        require_int(o, "stall_steps", self.stall_steps, 2)


@dataclass(frozen=True)
class VFFParams:
    """VFF force constants (eq. 2.1-2.6) and the robot.

    Attributes:
        f_cr: repulsive force constant Fcr.
        f_ct: attractive (target) force constant Fct.
        k_s: steering gain Ks (per step, applied to the signed angle error).
        robot: the simulated robot (:class:`RobotParams`).
    """

    f_cr: float = 0.05
    f_ct: float = 1.0
    k_s: float = 0.3
    robot: RobotParams = RobotParams()

    def __post_init__(self) -> None:
        for name in ("f_cr", "f_ct", "k_s"):
            require_positive("VFFParams", name, getattr(self, name))


def _result(world: GridWorld, code: int, traj: np.ndarray, name: str, runtime: float,
            goal: tuple[int, int]) -> PlanResult:
    info: dict[str, Any] = {"outcome": OUTCOMES[code].split(":")[0] if code else "reached",
                            "steps": int(traj.shape[0] - 1),
                            "trajectory": traj}
    if code == K.REACHED:
        path = np.vstack([traj, np.asarray(goal, dtype=float)])
        return PlanResult(simplify(path), True, "ok", name, runtime,
                          info={**info, "driven_length": float(
                              np.sum(np.hypot(*np.diff(path, axis=0).T)))})
    at = traj[-1]
    return PlanResult(np.zeros((0, 2)), False,
                      f"{OUTCOMES[code]} at ({at[0]:.2f}, {at[1]:.2f}) after "
                      f"{traj.shape[0] - 1} steps", name, runtime, info=info)


def simplify(path: np.ndarray, tol: float = 0.05) -> np.ndarray:
    """Ramer-Douglas-Peucker: drop points within ``tol`` cells of the chord
    (a driven trajectory has a point per step; turns are counted on this)."""
    path = np.asarray(path, dtype=float)
    if path.shape[0] < 3:
        return path.copy()
    keep = np.zeros(path.shape[0], dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, path.shape[0] - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        a, b = path[i], path[j]
        ab = b - a
        n = math.hypot(*ab)
        seg = path[i + 1:j] - a
        if n == 0:
            d = np.hypot(seg[:, 0], seg[:, 1])
        else:
            d = np.abs(ab[0] * seg[:, 1] - ab[1] * seg[:, 0]) / n
        k = int(np.argmax(d))
        if d[k] > tol:
            keep[i + 1 + k] = True
            stack.extend([(i, i + 1 + k), (i + 1 + k, j)])
    return path[keep]


def plan(world: GridWorld, start: Any, goal: Any, *, params: VFFParams | None = None,
         seed: int | None = None) -> PlanResult:
    """Drive from ``start`` to ``goal`` with the virtual force field.

    Deterministic (``seed`` is accepted for a uniform interface). The path is
    the driven trajectory, simplified (:func:`simplify`); ``info`` holds the
    outcome, the number of steps and the raw trajectory.

    Raises:
        UnreachableError: start or goal outside the grid or blocked.
    """
    params = params or VFFParams()
    r = params.robot
    s = world.check_cell("start", start)
    g = world.check_cell("goal", goal)
    p = np.array([r.window, params.f_cr, params.f_ct, params.k_s, math.radians(r.max_turn_deg),
                  r.speed, r.max_steps, r.goal_tolerance, r.stall_steps, r.stall_gain,
                  r.certainty_increment, r.certainty_max])
    t0 = time.perf_counter()
    code, traj = K.vff_run(world.occupancy.view(np.uint8), float(s[0]), float(s[1]),
                           float(g[0]), float(g[1]), p)
    return _result(world, int(code), traj, "vff", time.perf_counter() - t0, g)
