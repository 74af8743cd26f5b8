"""Collision-free legs around obstacles: OMPL's RRTConnect in joint space, then timed.

A leg whose straight joint-space line collides
(:meth:`~subtask_opt.cell.scene.CollisionChecker.leg_in_collision`) is planned by
:func:`plan_detour`:

1. OMPL's RRTConnect (the ``ompl`` wheel; Kuffner and LaValle's bidirectional RRT) in the
   box of the joint limits, with the collision checker as the state validity callback.
   OMPL checks each motion at states no farther apart (Euclidean, in radians) than
   ``coarse * clearance / |R|``, where R are the checker's sweep radii
   (:attr:`~subtask_opt.cell.scene.CollisionChecker.sweep_radii`; with ``coarse`` 1 no
   point of the arm or the tool moves more than the clearance between two checked states,
   the same rule as the straight legs' sweep).
2. OMPL's path simplifier (shortcuts, vertex reduction, collapsing), which keeps the path
   collision-free under the same check.
3. Every segment of the result is swept again with ``leg_in_collision`` (our check, not
   OMPL's), so a detour is collision-free by the same rule as a straight leg, then
   greedily shortcut by that sweep (each waypoint is a stop, see 4). ``attempts`` plans
   with different seeds are made and the fastest kept.
4. Timing: rest-to-rest ruckig moves chained through the waypoints, each along its
   straight joint-space segment (:func:`~subtask_opt.kinematics.joint_moves.joint_move`,
   phase-synchronised, the arm's velocity, acceleration and jerk limits). ruckig's
   intermediate waypoints are a Pro feature and toppra's splines through the waypoints
   would leave the checked segments, so the arm stops at each waypoint: the time is an
   upper bound of what a blended path could do, and exactly what is executed.

The planner's work is bounded by validity checks, not wall time (``DetourParams``), so
the same seed gives the same path in every process: OMPL's random generator is seeded
(``ompl.util.RNG.setSeed``) before each plan from the call's seed and the leg's end
configurations, under a lock (OMPL's seed is process-wide), so a leg's detour does not
depend on which legs were planned before it.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_in_range, require_int
from subtask_opt.kinematics.joint_moves import JointLimits, joint_leg_times, ruckig_leg_time

if TYPE_CHECKING:
    from subtask_opt.cell.scene import CollisionChecker

_OMPL_LOCK = threading.Lock()


@dataclass(frozen=True)
class DetourParams:
    """Budgets of the leg planner.

    Attributes:
        max_checks: most state-validity checks one plan (RRTConnect) may make; the
            simplifier gets a quarter as many more. A plan that runs out fails (the leg stays
            forbidden).
        max_plans: most legs one solve plans (the lazy search's budget); the legs in
            collision found after that are forbidden, as with ``detours=False``.
        attempts: independent plans (seeds derived from the leg's) of each leg of the
            final tour; the fastest executed path is kept (RRTConnect's paths vary
            widely). The lazy search plans each leg once (its first attempt); the legs
            its answer drives are planned ``attempts`` times, which can only shorten them.
        range: RRTConnect's step (rad, Euclidean in joint space); 0: OMPL's default
            (a fifth of the planning box's diagonal).
        margin: the planning box is the joint limits cut to the leg's ends' box grown by
            ``margin`` rad per joint (a UR's +-2 pi joints would let the tree wander
            around full turns).
        coarse: OMPL checks motions ``coarse`` times more sparsely than the clearance
            rule (step 1 of the module doc); the result is swept by our own check at the
            clearance (step 3), and a path that fails it is planned again at the full
            resolution (``coarse`` 1), so only the planner's speed depends on it.
    """

    max_checks: int = 20_000
    max_plans: int = 100
    attempts: int = 4
    range: float = 1.0
    margin: float = np.pi
    coarse: float = 4.0

    def __post_init__(self) -> None:
        require_int("DetourParams", "max_checks", self.max_checks, 100, 10_000_000)
        require_int("DetourParams", "max_plans", self.max_plans, 0, 100_000)
        require_int("DetourParams", "attempts", self.attempts, 1, 100)
        require_in_range("DetourParams", "range", self.range, 0.0, 100.0)
        require_in_range("DetourParams", "margin", self.margin, 0.0, 100.0)
        require_in_range("DetourParams", "coarse", self.coarse, 1.0, 100.0)


@dataclass(frozen=True, eq=False)
class Detour:
    """A planned collision-free leg.

    Attributes:
        waypoints: (k, n) joint vectors, the leg's two ends first and last (k >= 3).
        planned_time: sum of the segments' phase-synchronised times (the search's model).
        executed_time: sum of ruckig's times of the same segments.
        checks: validity checks the planner and simplifier made.
        cpu: CPU seconds of planning, simplifying and re-checking.
    """

    waypoints: np.ndarray
    planned_time: float
    executed_time: float
    checks: int
    cpu: float

    def reversed(self) -> Detour:
        """The same detour driven the other way."""
        return Detour(self.waypoints[::-1].copy(), self.planned_time, self.executed_time,
                      self.checks, self.cpu)


def detour_times(waypoints: np.ndarray, limits: JointLimits, jerk: Any) -> tuple[float, float]:
    """(planned, executed) time of rest-to-rest moves through ``waypoints``."""
    planned = executed = 0.0
    for a, b in zip(waypoints[:-1], waypoints[1:], strict=True):
        planned += float(joint_leg_times(a, b, limits)[0, 0])
        executed += ruckig_leg_time(a, b, limits.velocity, limits.acceleration, jerk)
    return planned, executed


def leg_seed(seed: int, q0: np.ndarray, q1: np.ndarray) -> int:
    """OMPL's seed for the leg q0 -> q1 (in [1, 2**31)): the call's seed and the two ends."""
    words = np.concatenate([np.round(q0, 9), np.round(q1, 9)]).view(np.uint64)
    state = np.random.SeedSequence([int(seed) % 2**63, *[int(w) for w in words]])
    return int(state.generate_state(1, dtype=np.uint32)[0]) % (2**31 - 1) + 1


def _shortcut(checker: CollisionChecker, waypoints: np.ndarray, clearance: float) -> np.ndarray:
    """Greedy shortcuts by our own sweep: from each kept waypoint, straight to the farthest
    later one the sweep finds free (each stop costs a rest-to-rest move)."""
    kept = [0]
    last = len(waypoints) - 1
    while kept[-1] < last:
        i = kept[-1]
        j = next(j for j in range(last, i, -1)
                 if j == i + 1 or not checker.leg_in_collision(waypoints[i], waypoints[j],
                                                               clearance))
        kept.append(j)
    return np.ascontiguousarray(waypoints[kept])


def plan_detour(checker: CollisionChecker, q0: Any, q1: Any, *, clearance: float,
                limits: JointLimits, jerk: Any = None, seed: int = 0,
                params: DetourParams | None = None, attempts: int | None = None
                ) -> Detour | None:
    """A collision-free path q0 -> q1 (see the module doc), or None when the planner fails
    within its budget.

    Raises:
        ParameterError: a bad clearance, seed or params.
    """
    params = params if params is not None else DetourParams()
    if not isinstance(params, DetourParams):
        raise ParameterError(f"plan_detour: params must be DetourParams, got {params!r}")
    require_in_range("plan_detour", "clearance", clearance, 1e-6, 10.0)
    require_int("plan_detour", "seed", seed, 0, 2**63 - 1)
    arm = checker.arm
    a = arm.check_q(q0)
    b = arm.check_q(q1)
    t0 = time.process_time()
    best: Detour | None = None
    checks = 0
    tries = params.attempts if attempts is None else attempts
    require_int("plan_detour", "attempts", tries, 1, 100)
    for attempt in range(tries):
        ompl_seed = leg_seed(seed + attempt, a, b)
        found, calls = _plan_once(checker, a, b, clearance, limits, jerk, ompl_seed, params,
                                  params.coarse)
        checks += calls
        if found is None and params.coarse > 1.0:  # our sweep may refute a coarse path
            found, calls = _plan_once(checker, a, b, clearance, limits, jerk, ompl_seed,
                                      params, 1.0)
            checks += calls
        if found is not None and (best is None or found.executed_time < best.executed_time):
            best = found
    if best is None:
        return None
    return Detour(best.waypoints, best.planned_time, best.executed_time, checks,
                  time.process_time() - t0)


def _plan_once(checker: CollisionChecker, a: np.ndarray, b: np.ndarray, clearance: float,
               limits: JointLimits, jerk: Any, ompl_seed: int, params: DetourParams,
               coarse: float) -> tuple[Detour | None, int]:
    """One RRTConnect plan, simplified and re-checked, and the validity checks it made."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    arm = checker.arm
    n = arm.nq
    lower = np.maximum(np.asarray(arm.limits.lower, dtype=float),
                       np.minimum(a, b) - params.margin)
    upper = np.minimum(np.asarray(arm.limits.upper, dtype=float),
                       np.maximum(a, b) + params.margin)
    step = coarse * clearance / max(float(np.linalg.norm(checker.sweep_radii)), 1e-9)
    calls = [0]

    def valid(state: Any) -> bool:
        calls[0] += 1
        return not checker.collides_fast(np.clip(np.array(state[0:n]), lower, upper))

    with _OMPL_LOCK:
        level = ou.getLogLevel()
        ou.setLogLevel(ou.LOG_NONE)  # OMPL warns when a seed is set after the first plan
        try:
            ou.RNG.setSeed(ompl_seed)
            space = ob.RealVectorStateSpace(n)
            bounds = ob.RealVectorBounds(n)
            for j in range(n):
                bounds.setLow(j, float(lower[j]))
                bounds.setHigh(j, float(upper[j]))
            space.setBounds(bounds)
            si = ob.SpaceInformation(space)
            si.setStateValidityChecker(valid)
            si.setStateValidityCheckingResolution(
                min(1.0, step / max(space.getMaximumExtent(), 1e-12)))
            si.setup()
            start, goal = si.allocState(), si.allocState()
            for j in range(n):
                start[j] = float(a[j])
                goal[j] = float(b[j])
            pdef = ob.ProblemDefinition(si)
            pdef.setStartAndGoalStates(start, goal)
            planner = og.RRTConnect(si)
            if params.range > 0:
                planner.setRange(params.range)
            planner.setProblemDefinition(pdef)
            planner.setup()
            budget = params.max_checks
            status = planner.solve(ob.PlannerTerminationCondition(lambda: calls[0] > budget))
            if not pdef.hasExactSolution() or "Exact" not in str(status):
                return None, calls[0]
            path = pdef.getSolutionPath()
            limit = calls[0] + params.max_checks // 4
            og.PathSimplifier(si).simplify(
                path, ob.PlannerTerminationCondition(lambda: calls[0] > limit), True)
            waypoints = np.array([[s[j] for j in range(n)] for s in path.getStates()])
        finally:
            ou.setLogLevel(level)
    waypoints = np.clip(waypoints, lower, upper)
    waypoints[0], waypoints[-1] = a, b  # exactly the leg's ends
    keep = [0] + [k for k in range(1, len(waypoints))
                  if np.abs(waypoints[k] - waypoints[k - 1]).max() > 1e-12]
    waypoints = waypoints[keep]
    if len(waypoints) < 3 or any(checker.leg_in_collision(waypoints[k], waypoints[k + 1],
                                                          clearance)
                                 for k in range(len(waypoints) - 1)):
        return None, calls[0]
    waypoints = _shortcut(checker, waypoints, clearance)
    if len(waypoints) < 3:
        return None, calls[0]  # straight (it collides), or a segment our sweep finds colliding
    planned, executed = detour_times(waypoints, limits, jerk)
    waypoints.setflags(write=False)
    return Detour(waypoints, planned, executed, calls[0], 0.0), calls[0]


__all__ = ["Detour", "DetourParams", "detour_times", "leg_seed", "plan_detour"]
