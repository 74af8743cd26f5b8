"""Simulation of a reactive navigator in a polygon world, the reactive planners, and suites.

:func:`simulate` closes the loop sense -> decide -> move at the robot's sampling
time until the run ends, which it always does (:class:`~subtask_opt.base.results.Outcome`):

* ``success``: the robot centre is within ``goal_tolerance`` of the goal;
* ``collision``: the body circle meets an obstacle or the world boundary
  (an exact swept test along each arc, :func:`._kernels.swept_clearance`;
  the run stops at the point of contact);
* ``stall``: the best distance to the goal has not improved by
  ``progress_tol`` for ``stall_steps`` steps (trapped, circling or stopped);
* ``timeout``: ``max_steps`` sampling periods elapsed.

The :class:`ReactiveRun` keeps the whole trace (poses, scans, commands, the
chosen candidate's memberships, escape flags, targets) for plots and the GIF.

Planners: the navigators ``fuzzy``, ``fuzzy-no-escape``, ``vff`` and ``vfh``
are registered in family ``"reactive"`` with the common protocol
``plan(world, start, goal, *, params=None, seed=None, stop=None) -> PlanResult``
(``params``: one :class:`ReactiveParams`; ``seed``: the sensor noise; the
path is the driven trajectory). :func:`plan` is the same with a
``navigator`` keyword.

Suites: :func:`run_navigation_suite` runs several navigators on the same
scenarios, :func:`navigation_suite_summary` reduces the runs to the table of
``bench reactive`` and :func:`benchmark_navigators` does both on seeded
random worlds.

Threads: worlds, :class:`ReactiveParams` and everything in it are immutable
and may be shared by any number of threads; :func:`simulate` builds a fresh
navigator for every run given by name. A navigator *object* keeps the state
of its run (the wall-following episode): give each thread its own.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any, Protocol

import numpy as np

from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    UnreachableError,
    require_int,
    require_positive,
)
from subtask_opt.base.geometry import polyline_length
from subtask_opt.base.progress import progress_bar
from subtask_opt.base.results import Outcome, PlanResult
from subtask_opt.planners.base import check_seed, register
from subtask_opt.planners.polygon.world import PolygonWorld
from subtask_opt.planners.reactive import _kernels as K
from subtask_opt.planners.reactive.baselines import (
    SonarVFFParams,
    SonarVFHParams,
    VFFNavigator,
    VFHNavigator,
)
from subtask_opt.planners.reactive.fuzzy import FuzzyNavigator, FuzzyParams, NavDecision
from subtask_opt.planners.reactive.scenarios import (
    RandomSuiteParams,
    Scenario,
    random_navigation_suite,
)
from subtask_opt.planners.reactive.sonar import SonarRing, scene_edges
from subtask_opt.planners.reactive.unicycle import Unicycle, integrate_arc

NAVIGATORS = ("fuzzy", "fuzzy-no-escape", "vff", "vfh")
"""The navigators :func:`simulate` builds by name (and the registered planners)."""

MEMORY_LIMIT = 1 << 30
"""Largest memory (bytes) a run's record and scratch may take (1 GiB)."""

MAX_SWEEP_SAMPLES = 64
"""Most evenly spaced samples of the body along one step before refinement."""


class Navigator(Protocol):
    """What :func:`simulate` drives: a name, ``reset()`` and ``decide(pose, ranges, goal)``."""

    name: str

    def reset(self) -> None: ...

    def decide(self, pose: np.ndarray, ranges: np.ndarray, goal: np.ndarray) -> NavDecision: ...


@dataclass(frozen=True)
class SimParams:
    """When a run ends.

    Attributes:
        goal_tolerance: success radius around the goal (> 0).
        max_steps: sampling periods before a timeout (>= 1; the memory the
            record needs is checked by :class:`ReactiveParams`).
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


def _require_type(owner: str, name: str, value: Any, cls: type) -> None:
    if not isinstance(value, cls):
        raise ParameterError(f"{owner}.{name} must be a {cls.__name__}, got "
                             f"{type(value).__name__}")


@dataclass(frozen=True)
class ReactiveParams:
    """Everything a reactive run needs besides the world, start, goal and seed.

    Attributes:
        robot: the unicycle (limits, sampling time, body radius).
        sonar: the sensor ring (beams, range, noise).
        sim: end conditions (goal tolerance, step limit, stall detection).
        fuzzy: the fuzzy navigator's settings (``escape`` is set by the
            navigator's name: ``fuzzy`` escapes, ``fuzzy-no-escape`` does not).
        vff, vfh: the baselines' settings.

    Raises:
        ParameterError: a field of the wrong type; a step longer than the
            sonar range (``max_speed * dt > max_range``: the robot would drive
            into space it has not sensed); or a run whose record and scratch
            would exceed :data:`MEMORY_LIMIT` (the message gives the estimate).
    """

    robot: Unicycle = field(default_factory=Unicycle)
    sonar: SonarRing = field(default_factory=SonarRing)
    sim: SimParams = field(default_factory=SimParams)
    fuzzy: FuzzyParams = field(default_factory=FuzzyParams)
    vff: SonarVFFParams = field(default_factory=SonarVFFParams)
    vfh: SonarVFHParams = field(default_factory=SonarVFHParams)

    def __post_init__(self) -> None:
        for name, cls in (("robot", Unicycle), ("sonar", SonarRing), ("sim", SimParams),
                          ("fuzzy", FuzzyParams), ("vff", SonarVFFParams),
                          ("vfh", SonarVFHParams)):
            _require_type("ReactiveParams", name, getattr(self, name), cls)
        if self.robot.max_step > self.sonar.max_range:
            raise ParameterError(
                f"ReactiveParams: one step (max_speed * dt = {self.robot.max_speed:g} * "
                f"{self.robot.dt:g} = {self.robot.max_step:g}) must not exceed the sonar "
                f"range max_range = {self.sonar.max_range:g}")
        need = self.memory_estimate()
        if need > MEMORY_LIMIT:
            raise ParameterError(
                f"ReactiveParams: a run of max_steps = {self.sim.max_steps} with "
                f"{self.sonar.n_beams} beams and {self._candidates()} via-point candidates "
                f"would need about {need / 2**20:,.0f} MiB, more than the limit of "
                f"{MEMORY_LIMIT / 2**20:,.0f} MiB; lower max_steps")

    def _candidates(self) -> int:
        return self.fuzzy.n_headings * self.fuzzy.n_speeds

    def memory_estimate(self) -> int:
        """Bytes a run may need: the per-step record (pose, scan, command, memberships,
        target and their Python objects, then the final arrays) plus one decision's
        scratch (predicted scans of every candidate)."""
        n = self.sonar.n_beams
        per_step = 2 * (8 * (n + 12) + 600)
        record = (self.sim.max_steps + 2) * per_step
        decision = 3 * 8 * self._candidates() * (n + 8)
        return int(record + decision)


def make_navigator(name: str, params: ReactiveParams | None = None) -> Navigator:
    """A fresh navigator by name, one of :data:`NAVIGATORS`."""
    p = params or ReactiveParams()
    if name == "fuzzy" or name == "fuzzy-no-escape":
        escape = name == "fuzzy"
        fuzzy = p.fuzzy if p.fuzzy.escape == escape else replace(p.fuzzy, escape=escape)
        return FuzzyNavigator(p.robot, p.sonar, fuzzy)
    if name == "vff":
        return VFFNavigator(p.robot, p.sonar, p.vff)
    if name == "vfh":
        return VFHNavigator(p.robot, p.sonar, p.vfh)
    raise ParameterError(f"navigator must be one of {list(NAVIGATORS)}, got {name!r}")


@dataclass(frozen=True)
class ReactiveRun:
    """The record of one simulated run (n decision steps).

    Attributes:
        navigator, world: names.
        start: (3,) start pose; goal: (2,) goal.
        poses: (n + 1, 3) poses, the start first (after a collision, the last
            pose is where the body first touched).
        scans: (n + 1, n_beams) readings taken at each pose.
        commands: (n, 2) speed and turn rate held over each step (after a
            collision the last one is scaled to the point of contact, so every
            pose follows from the one before and its command).
        mu: (n, 4) muG1, muG2, muG3, muD of each chosen candidate (NaN for baselines).
        escaping: (n,) whether each step was wall following.
        targets: (n, 2) goal or virtual target of each step.
        outcome: how the run ended; message: a readable reason.
        dt: sampling time; radius: body radius; beam_angles: sensor angles (robot frame);
        max_range: sensor range; goal_tolerance: success radius.
        min_clearance: smallest body clearance (centre distance minus radius) sampled.
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
    outcome: Outcome
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
        return self.outcome == Outcome.SUCCESS

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
        """The run as the planners' common :class:`PlanResult` (path = driven trajectory)."""
        return PlanResult(path=self.poses[:, :2].copy(), success=self.success,
                          message=self.message, planner=self.navigator,
                          runtime_s=self.runtime_s, info=self.summary_dict(),
                          outcome=self.outcome)

    def summary_dict(self) -> dict[str, Any]:
        """Scalar figures of the run (JSON-ready)."""
        return {"navigator": self.navigator, "world": self.world,
                "outcome": self.outcome.value, "message": self.message, "steps": self.steps,
                "time_s": self.time, "path_length": self.path_length,
                "min_clearance": self.min_clearance,
                "escape_steps": int(np.count_nonzero(self.escaping)),
                "runtime_s": self.runtime_s, "seed": self.seed}

    def to_dict(self) -> dict[str, Any]:
        """Everything, arrays as lists, NaN as None (for ``--json``)."""
        def listed(a: np.ndarray) -> list[Any]:
            if a.dtype.kind != "f":
                return list(a.tolist())
            obj = a.astype(object)
            obj[~np.isfinite(a)] = None
            return list(obj.tolist())

        out = self.summary_dict()
        out.update(start=listed(self.start), goal=listed(self.goal), dt=self.dt,
                   radius=self.radius, max_range=self.max_range,
                   beam_angles=listed(self.beam_angles), poses=listed(self.poses),
                   scans=listed(self.scans), commands=listed(self.commands),
                   mu=listed(self.mu), escaping=self.escaping.astype(int).tolist(),
                   targets=listed(self.targets))
        return out

    def summary(self) -> str:
        return (f"{self.navigator} on {self.world}: {self.outcome.value} ({self.message}) after "
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
             *, params: ReactiveParams | None = None, seed: int | None = None) -> ReactiveRun:
    """Drive ``navigator`` from ``start`` (x, y, heading) to ``goal`` (x, y) in ``world``.

    Args:
        world: the polygon world (its boundary counts as a wall).
        start: start pose; the body must be free there.
        goal: goal point, inside the bounds and outside every obstacle.
        navigator: a name from :data:`NAVIGATORS` (a fresh navigator is built)
            or a navigator object (reset first; not to be shared between threads).
        params: robot, sonar, end conditions and navigator settings.
        seed: seed of the sensor noise (used when ``params.sonar.noise_std > 0``),
            None or an integer in [0, 2**63).

    Raises:
        UnreachableError: start or goal outside the world or in an obstacle.
        InputDataError: malformed start or goal.
        ParameterError: bad navigator name, params or seed.
    """
    if not isinstance(world, PolygonWorld):
        raise InputDataError(f"world must be a PolygonWorld, got {type(world).__name__}")
    seed = check_seed(seed)
    p = params if params is not None else ReactiveParams()
    _require_type("simulate", "params", p, ReactiveParams)
    robot, sonar, sim = p.robot, p.sonar, p.sim
    s = _check_start(world, start, robot.radius)
    g = world.check_point("goal", goal)
    nav = make_navigator(navigator, p) if isinstance(navigator, str) else navigator
    nav.reset()
    rng = np.random.default_rng(seed)
    edges = scene_edges(world)
    sweep = K.SweepParams(
        radius=float(robot.radius),
        n_samples=min(MAX_SWEEP_SAMPLES, max(1, math.ceil(robot.max_step / (0.5 * robot.radius)))),
        tol=max(world.eps, 1e-12))

    t0 = time.perf_counter()
    pose = s.copy()
    poses, scans, cmds, mus, esc, targets = [pose], [], [], [], [], []
    best = math.hypot(*(g - pose[:2]))
    last_progress = 0
    min_clear = world.distance_to_obstacles(pose[:2]) - robot.radius
    outcome, message = Outcome.TIMEOUT, f"no arrival within {sim.max_steps} steps"
    for step in range(sim.max_steps + 1):
        ranges = sonar.scan(edges, pose, rng)
        scans.append(ranges)
        dist = math.hypot(g[0] - pose[0], g[1] - pose[1])
        if dist <= sim.goal_tolerance:
            outcome, message = Outcome.SUCCESS, f"goal reached within {sim.goal_tolerance:g}"
            break
        if step == sim.max_steps:
            break
        if dist < best - sim.progress_tol:
            best, last_progress = dist, step
        elif step - last_progress >= sim.stall_steps:
            outcome, message = Outcome.STALL, (f"no progress toward the goal for "
                                               f"{sim.stall_steps} steps")
            break
        d = nav.decide(pose, ranges, g)
        v, omega = robot.clip(d.v, d.omega)
        clear, hit, frac = K.swept_clearance(float(pose[0]), float(pose[1]), float(pose[2]),
                                             v, omega, robot.dt, edges, sweep)
        min_clear = min(min_clear, float(clear))
        if hit:
            v, omega = v * frac, omega * frac
        pose = integrate_arc(pose, v, omega, robot.dt)
        poses.append(pose)
        cmds.append((v, omega))
        mus.append(d.mu)
        esc.append(d.escaping)
        targets.append(d.target)
        if hit:
            outcome, message = Outcome.COLLISION, (f"body hit an obstacle near "
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
        goal_tolerance=sim.goal_tolerance, min_clearance=float(min_clear),
        runtime_s=time.perf_counter() - t0, seed=seed)


def plan(world: PolygonWorld, start: Any, goal: Any, *, params: ReactiveParams | None = None,
         seed: int | None = None, stop: Any = None, navigator: str = "fuzzy") -> PlanResult:
    """The planners' protocol: :func:`simulate` as a :class:`PlanResult`.

    The path is the driven trajectory; ``outcome`` tells success, collision,
    stall or timeout; ``info`` holds the run's scalar figures. ``stop`` must be
    None (a run ends by its own :class:`SimParams`).
    """
    if stop is not None:
        raise ParameterError(f"the reactive planners are not iterative: stop must be None, "
                             f"got {stop!r} (use ReactiveParams.sim.max_steps)")
    return simulate(world, start, goal, navigator, params=params, seed=seed).to_plan_result()


_DESCRIPTIONS = {
    "fuzzy": "fuzzy via-point selection with the local-minimum escape (seed paper 001)",
    "fuzzy-no-escape": "fuzzy via-point selection without the escape (trapped by a U)",
    "vff": "virtual force field on the sonar ring (Borenstein-Koren)",
    "vfh": "vector field histogram on the sonar ring (VFH+ style)",
}


def _registered(name: str) -> Callable[..., PlanResult]:
    def plan_navigator(world: PolygonWorld, start: Any, goal: Any, *,
                       params: ReactiveParams | None = None, seed: int | None = None,
                       stop: Any = None) -> PlanResult:
        return plan(world, start, goal, params=params, seed=seed, stop=stop, navigator=name)

    plan_navigator.__name__ = f"plan_{name.replace('-', '_')}"
    plan_navigator.__doc__ = (f"The ``{name}`` navigator as a planner: {_DESCRIPTIONS[name]}; "
                              "see :func:`plan`.")
    register("reactive", name, description=_DESCRIPTIONS[name], stochastic=True)(plan_navigator)
    return plan_navigator


plan_fuzzy = _registered("fuzzy")
plan_fuzzy_no_escape = _registered("fuzzy-no-escape")
plan_vff = _registered("vff")
plan_vfh = _registered("vfh")


# ---------------------------------------------------------------- suites

def suite_run(job: tuple[Scenario, str, int], params: ReactiveParams | None = None
              ) -> ReactiveRun:
    """One run of a suite: ``(scenario, navigator, noise seed)``; picklable for workers."""
    sc, name, noise_seed = job
    return simulate(sc.world, sc.start, sc.goal, name, params=params, seed=noise_seed)


def run_navigation_suite(scenarios: Sequence[Scenario], navigators: Sequence[str] = NAVIGATORS,
                         *, params: ReactiveParams | None = None, seed: int = 0,
                         progress: bool = False,
                         map_runs: Callable[[Callable[[Any], Any], list[Any]], list[Any]]
                         | None = None) -> dict[str, list[ReactiveRun]]:
    """Every navigator on every scenario; scenario i uses noise seed ``(seed + i) mod 2**63``.

    ``map_runs(fn, jobs)`` (default: a loop here, with a progress bar when
    ``progress``) returns ``[fn(j) for j in jobs]`` in order; pass one that runs
    them in parallel (:func:`subtask_opt.batch.suite_mapper`). A run depends on
    its scenario, navigator and seed only: the table is the same wherever it ran.
    """
    seed = check_seed(seed) or 0
    out: dict[str, list[ReactiveRun]] = {name: [] for name in navigators}
    for name in navigators:
        if name not in NAVIGATORS:
            raise ParameterError(f"navigator must be one of {list(NAVIGATORS)}, got {name!r}")
    jobs = [(sc, name, (seed + i) % 2**63) for i, sc in enumerate(scenarios) for name in out]
    one = partial(suite_run, params=params)
    if map_runs is None:
        runs = []
        with progress_bar(progress, total=len(jobs), desc="reactive", unit="run") as bar:
            for job in jobs:
                runs.append(one(job))
                bar.update()
    else:
        runs = map_runs(one, jobs)
    for (_, name, _), run in zip(jobs, runs, strict=True):
        out[name].append(run)
    return out


def navigation_suite_summary(runs: dict[str, list[ReactiveRun]],
                             shortest: Sequence[float] | None = None
                             ) -> dict[str, dict[str, Any]]:
    """Per navigator: runs, one count per outcome (success, collisions, stalls,
    timeouts), success rate, mean path ratio over successful runs (path length /
    ``shortest``), mean minimum clearance and mean wall time per run."""
    table: dict[str, dict[str, Any]] = {}
    for name, rs in runs.items():
        ok = [i for i, r in enumerate(rs) if r.success]
        ratio = float("nan")
        if shortest is not None and ok:
            ratio = float(np.mean([rs[i].path_length / shortest[i] for i in ok]))
        table[name] = {
            "runs": len(rs),
            "success": len(ok),
            "collisions": sum(r.outcome == Outcome.COLLISION for r in rs),
            "stalls": sum(r.outcome == Outcome.STALL for r in rs),
            "timeouts": sum(r.outcome == Outcome.TIMEOUT for r in rs),
            "success_rate": len(ok) / len(rs) if rs else float("nan"),
            "mean_path_ratio": ratio,
            "mean_min_clearance": float(np.mean([r.min_clearance for r in rs]))
            if rs else float("nan"),
            "mean_runtime_s": float(np.mean([r.runtime_s for r in rs])) if rs else float("nan"),
        }
    return table


def benchmark_navigators(n: int, seed: int, *, navigators: Sequence[str] = NAVIGATORS,
                         params: ReactiveParams | None = None,
                         suite: RandomSuiteParams | None = None, progress: bool = False,
                         map_runs: Callable[[Callable[[Any], Any], list[Any]], list[Any]]
                         | None = None) -> dict[str, dict[str, Any]]:
    """``n`` seeded random scenarios, every navigator on each; the
    :func:`navigation_suite_summary` table, path ratios taken against the exact
    shortest path (visibility graph) of each world."""
    from subtask_opt.planners.polygon.visibility import shortest_path_length

    seed = check_seed(seed) or 0
    scenarios = random_navigation_suite(n, seed, suite)
    runs = run_navigation_suite(scenarios, navigators, params=params, seed=seed,
                                progress=progress, map_runs=map_runs)
    shortest = [shortest_path_length(sc.world, sc.start[:2], sc.goal) for sc in scenarios]
    return navigation_suite_summary(runs, shortest)
