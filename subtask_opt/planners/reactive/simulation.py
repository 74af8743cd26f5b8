"""Simulation of a reactive navigator in a polygon world, and suites of such runs.

:func:`simulate` closes the loop sense -> decide -> move at the robot's sampling
time until the run ends, which it always does:

* ``success``: the robot centre is within ``goal_tolerance`` of the goal;
* ``collision``: the body circle meets an obstacle or the world boundary
  (checked along each step at spacing below the body radius, so no wall is
  jumped over);
* ``stall``: the best distance to the goal has not improved by
  ``progress_tol`` for ``stall_steps`` steps (trapped, circling or stopped);
* ``timeout``: ``max_steps`` sampling periods elapsed.

The :class:`ReactiveRun` keeps the whole trace (poses, scans, commands, the
chosen candidate's memberships, escape flags, targets) for plots and the GIF.
:func:`run_suite` runs several navigators on the same scenarios and
:func:`suite_summary` reduces the runs to the table of ``bench reactive``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    UnreachableError,
    require_int,
    require_positive,
)
from subtask_opt.base.progress import progress_bar
from subtask_opt.base.results import PlanResult, polyline_length
from subtask_opt.planners.polygon._kernels import distance_to_edges
from subtask_opt.planners.polygon.world import PolygonWorld
from subtask_opt.planners.reactive.baselines import VFFNavigator, VFFParams, VFHNavigator, VFHParams
from subtask_opt.planners.reactive.fuzzy import FuzzyNavigator, FuzzyParams, NavDecision
from subtask_opt.planners.reactive.scenarios import RandomSuiteParams, Scenario, random_suite
from subtask_opt.planners.reactive.sonar import SonarRing, scene_edges
from subtask_opt.planners.reactive.unicycle import Unicycle, integrate_arc

NAVIGATORS = ("fuzzy", "fuzzy-no-escape", "vff", "vfh")
OUTCOMES = ("success", "collision", "stall", "timeout")


class Navigator(Protocol):
    """What :func:`simulate` drives: a name, ``reset()`` and ``decide(pose, ranges, goal)``."""

    name: str

    def reset(self) -> None: ...

    def decide(self, pose: np.ndarray, ranges: np.ndarray, goal: np.ndarray) -> NavDecision: ...


def make_navigator(name: str, robot: Unicycle, sonar: SonarRing, *,
                   fuzzy: FuzzyParams | None = None, vff: VFFParams | None = None,
                   vfh: VFHParams | None = None) -> Navigator:
    """A navigator by name: one of :data:`NAVIGATORS`."""
    if name == "fuzzy":
        params = fuzzy or FuzzyParams()
        if not params.escape:
            params = FuzzyParams(**{**params.__dict__, "escape": True})
        return FuzzyNavigator(robot, sonar, params)
    if name == "fuzzy-no-escape":
        params = FuzzyParams(**{**(fuzzy or FuzzyParams()).__dict__, "escape": False})
        return FuzzyNavigator(robot, sonar, params)
    if name == "vff":
        return VFFNavigator(robot, sonar, vff)
    if name == "vfh":
        return VFHNavigator(robot, sonar, vfh)
    raise ParameterError(f"navigator must be one of {list(NAVIGATORS)}, got {name!r}")


@dataclass(frozen=True)
class SimParams:
    """When a run ends.

    Attributes:
        goal_tolerance: success radius around the goal (> 0).
        max_steps: sampling periods before a timeout (>= 1).
        stall_steps: periods without progress before a stall (>= 1).
        progress_tol: improvement of the best goal distance that counts as progress (> 0).
    """

    goal_tolerance: float = 0.25
    max_steps: int = 1500
    stall_steps: int = 200
    progress_tol: float = 0.05

    def __post_init__(self) -> None:
        require_positive("SimParams", "goal_tolerance", self.goal_tolerance)
        require_int("SimParams", "max_steps", self.max_steps, 1)
        require_int("SimParams", "stall_steps", self.stall_steps, 1)
        require_positive("SimParams", "progress_tol", self.progress_tol)


@dataclass(frozen=True)
class ReactiveRun:
    """The record of one simulated run (n decision steps).

    Attributes:
        navigator, world: names.
        start: (3,) start pose; goal: (2,) goal.
        poses: (n + 1, 3) poses, the start first.
        scans: (n + 1, n_beams) readings taken at each pose.
        commands: (n, 2) speed and turn rate held over each step.
        mu: (n, 4) muG1, muG2, muG3, muD of each chosen candidate (NaN for baselines).
        escaping: (n,) whether each step was wall following.
        targets: (n, 2) goal or virtual target of each step.
        outcome: one of :data:`OUTCOMES`; message: a readable reason.
        dt: sampling time; radius: body radius; beam_angles: sensor angles (robot frame);
        max_range: sensor range; goal_tolerance: success radius.
        min_clearance: smallest body clearance (centre distance minus radius) seen.
        runtime_s: wall time of the simulation; seed: the noise seed.
    """

    navigator: str
    world: str
    start: np.ndarray
    goal: np.ndarray
    poses: np.ndarray
    scans: np.ndarray
    commands: np.ndarray
    mu: np.ndarray
    escaping: np.ndarray
    targets: np.ndarray
    outcome: str
    message: str
    dt: float
    radius: float
    beam_angles: np.ndarray
    max_range: float
    goal_tolerance: float
    min_clearance: float
    runtime_s: float
    seed: int | None = None

    @property
    def success(self) -> bool:
        return self.outcome == "success"

    @property
    def steps(self) -> int:
        return int(self.commands.shape[0])

    @property
    def time(self) -> float:
        """Simulated time (s)."""
        return self.steps * self.dt

    @property
    def path_length(self) -> float:
        return polyline_length(self.poses[:, :2])

    def to_plan_result(self) -> PlanResult:
        """The run as the planners' common :class:`PlanResult` (path = trajectory)."""
        return PlanResult(path=self.poses[:, :2].copy(), success=self.success,
                          message=self.message, planner=self.navigator,
                          runtime_s=self.runtime_s, info=self.summary_dict())

    def summary_dict(self) -> dict[str, Any]:
        """Scalar figures of the run (JSON-ready)."""
        return {"navigator": self.navigator, "world": self.world, "outcome": self.outcome,
                "message": self.message, "steps": self.steps, "time_s": self.time,
                "path_length": self.path_length, "min_clearance": self.min_clearance,
                "escape_steps": int(np.count_nonzero(self.escaping)),
                "runtime_s": self.runtime_s, "seed": self.seed}

    def to_dict(self) -> dict[str, Any]:
        """Everything, arrays as lists (for ``--json``)."""
        out = self.summary_dict()
        out.update(start=self.start, goal=self.goal, dt=self.dt, radius=self.radius,
                   max_range=self.max_range, beam_angles=self.beam_angles,
                   poses=self.poses, scans=self.scans, commands=self.commands,
                   mu=self.mu, escaping=self.escaping.astype(int), targets=self.targets)
        return out

    def summary(self) -> str:
        return (f"{self.navigator} on {self.world}: {self.outcome} ({self.message}) after "
                f"{self.steps} steps / {self.time:.1f} s, path {self.path_length:.2f}, "
                f"min clearance {self.min_clearance:.3f}, {self.runtime_s * 1e3:.0f} ms")


def _check_start(world: PolygonWorld, start: Any, radius: float) -> np.ndarray:
    try:
        s = np.asarray(start, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputDataError(f"start must be three numbers x, y, heading, got {start!r}") from None
    if s.shape != (3,) or not np.all(np.isfinite(s)):
        raise InputDataError(f"start must be three finite numbers x, y, heading, got {start!r}")
    world.check_point("start", s[:2])
    if world.distance_to_obstacles(s[:2]) < radius:
        raise UnreachableError(f"start ({s[0]:g}, {s[1]:g}): the robot body (radius {radius:g}) "
                               "overlaps an obstacle or the boundary")
    return s


def simulate(world: PolygonWorld, start: Any, goal: Any, navigator: str | Navigator = "fuzzy",
             *, robot: Unicycle | None = None, sonar: SonarRing | None = None,
             fuzzy: FuzzyParams | None = None, params: SimParams | None = None,
             seed: int | None = None) -> ReactiveRun:
    """Drive ``navigator`` from ``start`` (x, y, heading) to ``goal`` (x, y) in ``world``.

    Args:
        world: the polygon world (its boundary counts as a wall).
        start: start pose; the body must be free there.
        goal: goal point, inside the bounds and outside every obstacle.
        navigator: a name from :data:`NAVIGATORS` or a navigator object.
        robot, sonar, fuzzy, params: robot, sensors, fuzzy settings, end conditions.
        seed: seed of the sensor noise (used when ``sonar.noise_std > 0``).

    Raises:
        UnreachableError: start or goal outside the world or in an obstacle.
        InputDataError: malformed start or goal.
    """
    robot = robot or Unicycle()
    sonar = sonar or SonarRing()
    params = params or SimParams()
    s = _check_start(world, start, robot.radius)
    g = world.check_point("goal", goal)
    nav = make_navigator(navigator, robot, sonar, fuzzy=fuzzy) if isinstance(navigator, str) \
        else navigator
    nav.reset()
    rng = np.random.default_rng(seed)
    edges = scene_edges(world)
    # body clearance is sampled at spacing <= radius / 2 along each step
    n_sub = max(1, math.ceil(robot.max_step / (0.5 * robot.radius)))
    fractions = np.arange(1, n_sub + 1) / n_sub

    t0 = time.perf_counter()
    pose = s.copy()
    poses, scans, cmds, mus, esc, targets = [pose], [], [], [], [], []
    best = math.hypot(*(g - pose[:2]))
    last_progress = 0
    min_clear = world.distance_to_obstacles(pose[:2]) - robot.radius
    outcome, message = "timeout", f"no arrival within {params.max_steps} steps"
    for step in range(params.max_steps + 1):
        ranges = sonar.scan(edges, pose, rng)
        scans.append(ranges)
        dist = math.hypot(g[0] - pose[0], g[1] - pose[1])
        if dist <= params.goal_tolerance:
            outcome, message = "success", f"goal reached within {params.goal_tolerance:g}"
            break
        if step == params.max_steps:
            break
        if dist < best - params.progress_tol:
            best, last_progress = dist, step
        elif step - last_progress >= params.stall_steps:
            outcome, message = "stall", (f"no progress toward the goal for "
                                         f"{params.stall_steps} steps")
            break
        d = nav.decide(pose, ranges, g)
        v, omega = robot.clip(d.v, d.omega)
        # the arc for a fraction f of dt is the arc of the command (f v, f omega) over dt
        sub = integrate_arc(pose, v * fractions, omega * fractions, robot.dt)
        clear = min(distance_to_edges(q[0], q[1], edges) for q in sub) - robot.radius
        min_clear = min(min_clear, clear)
        pose = robot.step(pose, v, omega)
        poses.append(pose)
        cmds.append((v, omega))
        mus.append(d.mu)
        esc.append(d.escaping)
        targets.append(d.target)
        if clear < 0.0:
            outcome, message = "collision", (f"body hit an obstacle near "
                                             f"({pose[0]:.2f}, {pose[1]:.2f})")
            scans.append(sonar.scan(edges, pose, rng))
            break
    n = len(cmds)
    return ReactiveRun(
        navigator=nav.name, world=world.name, start=s, goal=g, poses=np.array(poses),
        scans=np.array(scans), commands=np.array(cmds).reshape(n, 2),
        mu=np.array(mus).reshape(n, 4), escaping=np.array(esc, dtype=bool).reshape(n),
        targets=np.array(targets).reshape(n, 2), outcome=outcome, message=message,
        dt=robot.dt, radius=robot.radius, beam_angles=sonar.angles, max_range=sonar.max_range,
        goal_tolerance=params.goal_tolerance, min_clearance=float(min_clear),
        runtime_s=time.perf_counter() - t0, seed=seed)


def plan(world: PolygonWorld, start: Any, goal: Any, *, navigator: str = "fuzzy",
         robot: Unicycle | None = None, sonar: SonarRing | None = None,
         fuzzy: FuzzyParams | None = None, params: SimParams | None = None,
         seed: int | None = None) -> PlanResult:
    """The planners' common entry point: :func:`simulate` as a :class:`PlanResult`."""
    return simulate(world, start, goal, navigator, robot=robot, sonar=sonar, fuzzy=fuzzy,
                    params=params, seed=seed).to_plan_result()


def run_suite(scenarios: Sequence[Scenario], navigators: Sequence[str] = NAVIGATORS, *,
              robot: Unicycle | None = None, sonar: SonarRing | None = None,
              fuzzy: FuzzyParams | None = None, params: SimParams | None = None,
              seed: int = 0, progress: bool = False) -> dict[str, list[ReactiveRun]]:
    """Run every navigator on every scenario; scenario i uses noise seed ``seed + i``."""
    robot = robot or Unicycle()
    sonar = sonar or SonarRing()
    navs = [make_navigator(n, robot, sonar, fuzzy=fuzzy) for n in navigators]
    out: dict[str, list[ReactiveRun]] = {nav.name: [] for nav in navs}
    with progress_bar(progress, total=len(scenarios) * len(navs), desc="reactive",
                      unit="run") as bar:
        for i, sc in enumerate(scenarios):
            for nav in navs:
                out[nav.name].append(simulate(sc.world, sc.start, sc.goal, nav, robot=robot,
                                              sonar=sonar, params=params, seed=seed + i))
                bar.update()
    return out


def suite_summary(runs: dict[str, list[ReactiveRun]],
                  shortest: Sequence[float] | None = None) -> dict[str, dict[str, Any]]:
    """Per navigator: runs, success, collisions, timeouts (stalls included),
    success rate, mean path ratio over successful runs (path length / ``shortest``),
    mean minimum clearance and mean wall time per run."""
    table: dict[str, dict[str, Any]] = {}
    for name, rs in runs.items():
        ok = [i for i, r in enumerate(rs) if r.success]
        ratio = float("nan")
        if shortest is not None and ok:
            ratio = float(np.mean([rs[i].path_length / shortest[i] for i in ok]))
        table[name] = {
            "runs": len(rs),
            "success": len(ok),
            "collisions": sum(r.outcome == "collision" for r in rs),
            "timeouts": sum(r.outcome in ("stall", "timeout") for r in rs),
            "success_rate": len(ok) / len(rs) if rs else float("nan"),
            "mean_path_ratio": ratio,
            "mean_min_clearance": float(np.mean([r.min_clearance for r in rs]))
            if rs else float("nan"),
            "mean_runtime_s": float(np.mean([r.runtime_s for r in rs])) if rs else float("nan"),
        }
    return table


def benchmark(n: int, seed: int, *, navigators: Sequence[str] = ("fuzzy", "fuzzy-no-escape",
                                                               "vff", "vfh"),
              robot: Unicycle | None = None, sonar: SonarRing | None = None,
              suite: RandomSuiteParams | None = None, progress: bool = False
              ) -> dict[str, dict[str, Any]]:
    """``n`` seeded random scenarios, every navigator on each; the :func:`suite_summary`
    table, path ratios taken against the exact shortest path of each world."""
    from subtask_opt.planners.polygon.visibility import shortest_path_length

    scenarios = random_suite(n, seed, suite)
    runs = run_suite(scenarios, navigators, robot=robot, sonar=sonar, seed=seed,
                     progress=progress)
    shortest = [shortest_path_length(sc.world, sc.start[:2], sc.goal) for sc in scenarios]
    return suite_summary(runs, shortest)
