"""What VFF and VFH share: the simulated robot and the result of a drive.

A simulated point robot drives through the grid from the start cell centre,
one step of ``speed`` cells at a time. A step that touches a closed blocked
cell square (or leaves the grid) is a collision: the same rule as the exact
planners' line of sight (:func:`._kernels.move_clear`), so the robot never
passes through a blocked cell or between two blocked cells that touch at a
corner. Every run ends: at the goal, in a collision, in a detected stall
(local minimum or oscillation), with no free direction (VFH) or at the step
limit (outcome ``timeout``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_int, require_positive
from subtask_opt.base.geometry import polyline_length, simplify
from subtask_opt.base.results import Outcome, PlanResult
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid.world import GridWorld

#: Kernel outcome code -> (outcome, message).
OUTCOMES: dict[int, tuple[Outcome, str]] = {
    K.REACHED: (Outcome.SUCCESS, "ok"),
    K.COLLISION: (Outcome.COLLISION, "collision"),
    K.LOCAL_MINIMUM: (Outcome.STALL, "stall: local minimum (no progress towards the goal)"),
    K.OSCILLATION: (Outcome.STALL,
                    "stall: oscillation (moving without progress towards the goal)"),
    K.STEP_LIMIT: (Outcome.TIMEOUT, "timeout: step limit reached"),
    K.NO_VALLEY: (Outcome.STALL, "stall: no free direction"),
}


@dataclass(frozen=True)
class GridRobotParams:
    """The simulated robot of the grid VFF and VFH, and its run limits.

    Attributes:
        window: sensor / active-window radius, in cells.
        speed: distance per step, in cells (at most 0.5, so a step cannot jump a cell).
        max_turn_deg: largest heading change per step, in degrees.
        max_steps: step limit of a run (outcome ``timeout``).
        goal_tolerance: distance to the goal centre that counts as arrived
            (the last stretch onto the centre must be collision-free too).
        stall_steps: steps without ``stall_gain`` cells of progress that make a stall.
        stall_gain: progress towards the goal that resets the stall counter.
        stall_radius: a stalled robot that moved less than this (cells) over
            the last ``stall_steps`` steps is in a local minimum, else it oscillates.
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
    stall_radius: float = 1.0
    certainty_increment: float = 3.0
    certainty_max: float = 15.0

    def __post_init__(self) -> None:
        o = "GridRobotParams"
        for name in ("window", "speed", "max_turn_deg", "goal_tolerance", "stall_gain",
                     "stall_radius", "certainty_increment", "certainty_max"):
            require_positive(o, name, getattr(self, name))
        if self.speed > 0.5:
            raise ParameterError(f"{o}.speed must be in (0, 0.5] cells per step, "
                                 f"got {self.speed!r}")
        if self.max_turn_deg > 180:
            raise ParameterError(f"{o}.max_turn_deg must be in (0, 180], "
                                 f"got {self.max_turn_deg!r}")
        require_int(o, "max_steps", self.max_steps, 1, 10_000_000)
        require_int(o, "stall_steps", self.stall_steps, 2, 10_000_000)

    def kernel(self) -> K.RobotKernelParams:
        """The kernels' view (angles in radians)."""
        return K.RobotKernelParams(
            float(self.window), float(self.speed), math.radians(self.max_turn_deg),
            int(self.max_steps), float(self.goal_tolerance), int(self.stall_steps),
            float(self.stall_gain), float(self.stall_radius), float(self.certainty_increment),
            float(self.certainty_max))


def check_deterministic(name: str, seed: object, stop: object) -> None:
    """VFF and VFH take neither a seed nor a stopping criterion."""
    if seed is not None:
        raise ParameterError(f"{name} is deterministic: seed must be None, got {seed!r}")
    if stop is not None:
        raise ParameterError(f"{name} ends by its own step limit (GridRobotParams.max_steps): "
                             f"stop must be None, got {stop!r}")


def clear_simplify(world: GridWorld, path: np.ndarray, tol: float = 0.05) -> np.ndarray:
    """:func:`~subtask_opt.base.geometry.simplify` the driven path, then put back
    the driven points under every chord that would touch a blocked square, so
    the simplified path is as collision-free as the drive."""
    blocked = world.occupancy.view(np.uint8)
    short = simplify(path, tol)
    if short.shape[0] == path.shape[0]:
        return short
    # indices of the kept points in the driven path (simplify keeps a subsequence)
    idx = np.zeros(short.shape[0], dtype=np.int64)
    j = 0
    for i, p in enumerate(path):
        if j < short.shape[0] and np.array_equal(p, short[j]):
            idx[j] = i
            j += 1
    keep: list[int] = [int(idx[0])]
    for a, b in zip(idx[:-1], idx[1:], strict=True):
        pa, pb = path[a], path[b]
        if not K.move_clear(blocked, pa[0], pa[1], pb[0], pb[1]):
            keep.extend(range(int(a) + 1, int(b)))
        keep.append(int(b))
    return path[keep]


def drive(name: str, run: Callable[..., tuple[int, np.ndarray]], world: GridWorld, start: Any,
          goal: Any, robot: GridRobotParams, algorithm: Any, *, seed: object = None,
          stop: object = None) -> PlanResult:
    """The ``plan`` of VFF and VFH: check the arguments, drive, return the result.

    Args:
        name: the planner's name (``"vff"`` or ``"vfh"``).
        run: its kernel (:func:`._kernels.vff_run` or :func:`._kernels.vfh_run`).
        world, start, goal: as for every grid planner.
        robot: the simulated robot.
        algorithm: the kernel's own parameters (a ``*KernelParams`` NamedTuple).
        seed, stop: must be None (:func:`check_deterministic`).

    Returns:
        :func:`drive_result` of the run.

    Raises:
        UnreachableError: start or goal outside the grid or blocked.
        ParameterError: a seed or a stopping criterion was given.
    """
    check_deterministic(name, seed, stop)
    s = world.check_cell("start", start)
    g = world.check_cell("goal", goal)
    t0 = time.perf_counter()
    code, traj = run(world.occupancy.view(np.uint8), float(s[0]), float(s[1]),
                     float(g[0]), float(g[1]), robot.kernel(), algorithm)
    return drive_result(world, int(code), traj, name, time.perf_counter() - t0, g)


def drive_result(world: GridWorld, code: int, traj: np.ndarray, name: str, runtime: float,
                 goal: tuple[int, int]) -> PlanResult:
    """The :class:`PlanResult` of a drive.

    Success: the path is the driven trajectory plus the goal centre,
    simplified (:func:`clear_simplify`). Failure: an empty path, the outcome
    (``collision``, ``stall`` or ``timeout``) and where it happened. ``info``
    holds ``steps``, ``driven_length`` and the driven ``trajectory`` as a
    JSON list of ``[x, y]`` points (the start included).
    """
    outcome, reason = OUTCOMES[code]
    steps = int(traj.shape[0] - 1)
    info: dict[str, Any] = {"steps": steps, "kernel_outcome": reason.split(":")[0]}
    if outcome == Outcome.SUCCESS:
        driven = np.vstack([traj, np.asarray(goal, dtype=float)])
        info.update(driven_length=polyline_length(driven), trajectory=driven.tolist())
        return PlanResult(clear_simplify(world, driven), True, "ok", name, runtime, info=info)
    info.update(driven_length=polyline_length(traj), trajectory=traj.tolist())
    at = traj[-1]
    return PlanResult(np.zeros((0, 2)), False,
                      f"{reason} at ({at[0]:.2f}, {at[1]:.2f}) after {steps} steps", name,
                      runtime, info=info, outcome=outcome)
