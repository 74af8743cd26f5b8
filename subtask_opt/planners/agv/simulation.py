"""AGV among moving obstacles (seed 004) as a fixed-step simulation: corner
sub-goals on the 2-bit local map, the quadtree check of the next leg, the
t-second collision check, crossing rules, path recovery, and path following
with corner check points against odometry drift.

Geometry is in cells of the global map (x = column, y = row, a cell centre at
integer coordinates; one cell = one paper unit u = 10 x 10 pixels); time in
seconds. The AGV and the obstacles are discs moving at 1 u/s by default, like
the paper. The cell is ``cell_m`` metres (0.2 m by default), which maps the
sonar's 0.2-2 m range to 1-10 cells.

**Route.** The AGV plans on its *routing map*: only ``00`` cells of the local
map are routable (:mod:`.navigation`); a quadtree of that map partitions the free
space, gives the cost-to-go of the sub-goal choice (Dijkstra over its free
leaves), answers every line-of-sight question (a planned leg keeps
``wall_clearance`` from walls, a margin for the position error drift leaves)
and, when the AGV starts a new leg, checks the leg
ahead against the AGV's current map (static obstacles it has learned) and
reports seen obstacles standing in the leaves of that leg. Rules 1-5 (route
sections), 2-1 ... 2-7 (corners, with the reading of the unreachable rules
2-3 ... 2-6) and 3-1 ... 3-4 (navigation) are documented in
:mod:`.navigation`.

**t-second collision check (rule 3-3).** Every step, each obstacle within
sonar range gets the velocity of its last two positions; the AGV's motion
along its own path ahead at a candidate speed and the obstacles' straight
extrapolations are stepped forward for ``horizon_s`` (the time factor); the
candidate is safe when the predicted distance never falls below
``safety_distance`` (the distance factor); between two look-ahead steps the
closest approach is solved exactly, so a fast pass is not missed. Candidates:
keep cruising; brake to ``v_brake``; stop; speed up (the paper tries BRAKE
first, then SPEED_UP). When none keeps even ``pass_distance`` - an obstacle
comes at the AGV where it waits for another - the AGV backs off up to
``back_off`` along the way it came (if that predicts more room) and returns
once the way is clear.

**Crossing rules (§4.1 (5-2), §4.2.2).** The first point where an obstacle's
extrapolated ray meets the AGV's path decides who enters first:

* AGV first (5-2-1): the AGV keeps its normal speed as long as the look-ahead
  predicts a separation of at least ``pass_distance`` (a margin over
  ``collision_distance`` for what the prediction cannot know), otherwise it
  falls back to the collision check. The decision holds until the AGV gives
  way after all (brakes or stops for that obstacle): from then on who enters
  first is judged afresh. With ``speed_up_to_pass`` it speeds up to ``v_max``
  to pass instead (an option; not the paper's rule).
* Obstacle first (5-2-2): the t-second check decides (brake, stop, wait).
* Both at once (arrival times within ``priority_margin_s``): a sidestep via a
  point behind the obstacle's track ("the corner opposite the obstacle") at a
  speed similar to the obstacle's, then back onto the route (recovery).

An obstacle that stands still in front of the waiting AGV for
``static_after_s`` (~10 s) becomes static: its cells enter the AGV's map, the
quadtree is rebuilt, the AGV re-plans to the first point of its planned route
past the obstacle and then follows the rest of it (recovery, step 2-2 of the
paper's recovery algorithm). If the obstacle stands on the goal (or no detour
exists) the AGV logs ``blocked`` and keeps waiting: the run ends in a timeout
unless the obstacle leaves - the input is not to blame.

**Path following (§3.3.2).** With ``drift`` on, the AGV's odometry is wrong:
its true step is its commanded step turned by a heading error (a seeded
per-run bias plus a random walk) and scaled by a seeded scale error, while it
believes it moved as commanded. Every ``check_interval_s`` (with
``check_points`` on) it measures the corners of the global map (and of the
room, where the border walls meet) within sonar range and the camera's field
of view by eq. (3): ``TH = arctan(theta_x / f)`` (bearing of the corner from
the image column ``theta_x`` and the focal length ``f``) and ``X = L cos(TH) /
tan(K)`` (distance from the sensor height ``L`` and the depression angle
``K``). The nearest corner gives ``corner - X (cos, sin)(heading + TH)``,
which is off by ``X`` times the heading error: the AGV weighs it against its
dead reckoning by their expected errors (it tracks its own uncertainty from
the ``drift_*`` specification). Two corners at bearings far enough apart fix
the position without the heading (the point at both distances ``X``) and then
the heading itself, which calibrates the odometry's heading error. After a fix
the AGV steers back onto its planned leg (``track_lookahead``) rather than
heading for the next sub-goal along a line nobody checked against the walls.
:attr:`AgvRun.drift_error` is ``|true - believed|`` at every step.

**Collisions.** A run ends in ``collision`` when the true centres come closer
than ``collision_distance`` at any time of a step (the closest approach of
the step's straight motions, not only its end) or when the true motion of a
step touches a blocked cell's closed square or leaves the map.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

import numpy as np

from subtask_opt.base.errors import (
    InputDataError,
    NoPathError,
    ParameterError,
    UnreachableError,
    require_non_negative,
    require_positive,
)
from subtask_opt.base.geometry import polyline_length, simplify, wrap_angle
from subtask_opt.base.results import Outcome, PlanResult
from subtask_opt.planners.agv import _kernels as K
from subtask_opt.planners.agv.navigation import (
    Section,
    build_tree,
    landmarks,
    navigate,
    room_corners,
    routing_map,
    segment_route,
    states_of_occupancy,
)
from subtask_opt.planners.agv.quadtree import Quadtree
from subtask_opt.planners.base import check_seed, register
from subtask_opt.planners.grid.world import GridWorld

EVENT_KINDS = ("subgoal", "section", "crossing", "brake", "wait", "speed_up", "back_off", "resume",
               "sidestep", "static", "replan", "recovery", "blocked", "check_point", "goal",
               "collision", "timeout", "no_path")

MAX_STEPS = 2_000_000
"""A run may take at most this many steps (``max_time_s / dt``)."""
MAX_HORIZON_STEPS = 10_000
"""The look-ahead may take at most this many steps (``horizon_s / dt``)."""
MAX_RUN_BYTES = 1 << 30
"""A run's recorded arrays may take at most this much memory (1 GiB)."""


# -- parameters and inputs ---------------------------------------------------------------
@dataclass(frozen=True)
class AgvParams:
    """Tuning of the AGV simulation (cells, seconds).

    Attributes:
        dt: simulation time step.
        v_nominal: cruising speed (paper: 1 u/s, one cell per second).
        v_max: speed when speeding up to pass (only with ``speed_up_to_pass``
            or when no slower choice is safe).
        v_brake: speed when braking to yield.
        a_max: acceleration limit (speed changes by at most ``a_max * dt`` a step).
        horizon_s: time factor of the t-second check (how far ahead it looks).
        safety_distance: distance factor: a prediction closer than this is a conflict.
        collision_distance: centres closer than this collide (sum of body radii).
        pass_distance: when the AGV enters a crossing first it keeps its speed
            only while the look-ahead predicts at least this separation (the
            margin over ``collision_distance`` absorbs what the prediction
            cannot know: the heading error of drift, obstacles that turn).
        cell_m: side of a cell in metres (maps the sonar range to cells).
        sonar_min_m, sonar_max_m: sonar range (paper: 0.2 m - 2 m); check
            points are measured only in it, obstacles are first seen within
            ``sonar_max_m`` and stay tracked when they come closer than
            ``sonar_min_m``.
        static_after_s: an obstacle standing in front this long becomes static.
        static_radius: cells whose centre lies within this of a static obstacle
            are blocked in the AGV's map.
        priority_margin_s: arrival-time gap below which a crossing counts as
            simultaneous.
        sidestep_offset: how far behind the obstacle's track the sidestep point lies.
        turn_weight: weight of the turning angle (radians) in the corner value.
        max_time_s: a run that has not arrived by then ends in a timeout.
        collision_check: the t-second check (off: the AGV never brakes).
        crossing_rules: priority rules and sidesteps (off: brake first, as in the
            paper's bare algorithm).
        speed_up_to_pass: when the AGV enters a crossing first, speed up to
            ``v_max`` instead of keeping the normal speed (rule 5-2-1).
        drift: odometry drift (off in the paper's experiments).
        drift_heading_sd_deg: standard deviation of the per-run heading bias.
        drift_walk_deg: heading random walk, degrees per sqrt(second).
        drift_scale_sd: standard deviation of the per-run odometry scale error.
        check_points: correct the position at corners (§3.3.2) when drifting.
        check_interval_s: time between two check-point looks.
        camera_f_px: focal length ``f`` of eq. (3), pixels.
        camera_height: sensor height ``L`` of eq. (3), cells.
        camera_fov_deg: horizontal field of view; corners outside are not seen.
        open_leaf: quadtree leaves of at least this side are open road (rules 3-4).
        wall_clearance: every straight leg the AGV plans (route, detour,
            sidestep) keeps more than this distance (cells) from blocked cells
            and the map border, a margin for the position error left by drift
            and check points (below 0.5 one-cell corridors stay routable).
        back_off: when neither braking, stopping nor speeding up keeps even
            ``pass_distance`` (an obstacle comes at the AGV where it waits for
            another), it may back off this far (cells) along the way it came
            and return once the way is clear; 0: never.
        track_lookahead: path following: after a position fix the AGV steers
            back to its leg at the point this far (cells) ahead of its
            projection on it, instead of heading straight for the next
            sub-goal from wherever the fix put it.
    """

    dt: float = 0.25
    v_nominal: float = 1.0
    v_max: float = 1.5
    v_brake: float = 0.5
    a_max: float = 2.0
    horizon_s: float = 4.0
    safety_distance: float = 1.5
    collision_distance: float = 0.8
    pass_distance: float = 1.1
    cell_m: float = 0.2
    sonar_min_m: float = 0.2
    sonar_max_m: float = 2.0
    static_after_s: float = 10.0
    static_radius: float = 1.5
    priority_margin_s: float = 1.0
    sidestep_offset: float = 2.0
    turn_weight: float = 1.0
    max_time_s: float = 300.0
    collision_check: bool = True
    crossing_rules: bool = True
    speed_up_to_pass: bool = False
    drift: bool = False
    drift_heading_sd_deg: float = 2.0
    drift_walk_deg: float = 0.3
    drift_scale_sd: float = 0.03
    check_points: bool = True
    check_interval_s: float = 2.0
    camera_f_px: float = 500.0
    camera_height: float = 1.0
    camera_fov_deg: float = 120.0
    open_leaf: int = 4
    wall_clearance: float = 0.35
    back_off: float = 2.0
    track_lookahead: float = 1.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.type in ("bool", bool):
                if not isinstance(value, bool):
                    raise ParameterError(f"AgvParams.{f.name} must be a bool, got {value!r}")
            elif f.name in ("turn_weight", "drift_heading_sd_deg", "drift_walk_deg",
                            "drift_scale_sd", "wall_clearance", "back_off"):
                require_non_negative("AgvParams", f.name, value)
            elif f.name == "open_leaf":
                if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 2**20:
                    raise ParameterError(
                        f"AgvParams.open_leaf must be an integer in [1, 1048576], got {value!r}")
            else:
                require_positive("AgvParams", f.name, value)
        if not self.v_brake < self.v_nominal <= self.v_max:
            raise ParameterError(
                "AgvParams speeds must satisfy v_brake < v_nominal <= v_max, got "
                f"v_brake={self.v_brake!r}, v_nominal={self.v_nominal!r}, v_max={self.v_max!r}")
        if self.safety_distance < self.collision_distance:
            raise ParameterError(
                f"AgvParams.safety_distance must be >= collision_distance "
                f"({self.collision_distance!r}), got {self.safety_distance!r}")
        if not self.collision_distance <= self.pass_distance <= self.safety_distance:
            raise ParameterError(
                f"AgvParams.pass_distance must be in [collision_distance, safety_distance] "
                f"= [{self.collision_distance!r}, {self.safety_distance!r}], "
                f"got {self.pass_distance!r}")
        if self.sonar_min_m >= self.sonar_max_m:
            raise ParameterError(
                f"AgvParams.sonar_min_m must be < sonar_max_m ({self.sonar_max_m!r}), "
                f"got {self.sonar_min_m!r}")
        if self.camera_fov_deg >= 180:
            raise ParameterError(
                f"AgvParams.camera_fov_deg must be in (0, 180), got {self.camera_fov_deg!r}")
        if self.horizon_s < self.dt or self.max_time_s < self.dt:
            raise ParameterError(
                f"AgvParams.horizon_s and max_time_s must be >= dt ({self.dt!r}), got "
                f"{self.horizon_s!r} and {self.max_time_s!r}")
        steps = self.horizon_s / self.dt
        if steps > MAX_HORIZON_STEPS:
            raise ParameterError(
                f"AgvParams.horizon_s / dt = {steps:.3g} look-ahead steps; at most "
                f"{MAX_HORIZON_STEPS} are allowed (raise dt or lower horizon_s)")
        steps = self.max_time_s / self.dt
        if steps > MAX_STEPS:
            raise ParameterError(
                f"AgvParams.max_time_s / dt = {steps:.3g} steps; at most {MAX_STEPS} are "
                f"allowed (raise dt or lower max_time_s)")

    @property
    def sonar_range(self) -> tuple[float, float]:
        """The sonar range in cells (near, far)."""
        return self.sonar_min_m / self.cell_m, self.sonar_max_m / self.cell_m

    @classmethod
    def from_dict(cls, data: Any) -> AgvParams:
        """Build from a mapping; unknown keys are an error naming them."""
        if not isinstance(data, dict):
            raise InputDataError(f"AGV params must be a mapping, got {data!r:.80}")
        names = {f.name for f in fields(cls)}
        unknown = sorted(str(k) for k in set(data) - names)
        if unknown:
            raise ParameterError(
                f"unknown AgvParams field(s) {unknown}; allowed: {sorted(names)}")
        return cls(**data)


def run_size(params: AgvParams, n_obstacles: int) -> tuple[int, int]:
    """(steps, bytes) a run of these params with ``n_obstacles`` will record
    (its obstacle-free twin and the final copies included)."""
    steps = int(math.ceil(params.max_time_s / params.dt)) + 1
    per_step = 2 * (8 + 8 + 16 + 16 + 8) + 2 * 16 * n_obstacles
    return steps, steps * per_step


def check_run_size(params: AgvParams, n_obstacles: int) -> None:
    """Raise :class:`ParameterError` before a run would allocate over
    :data:`MAX_RUN_BYTES`."""
    steps, size = run_size(params, n_obstacles)
    if size > MAX_RUN_BYTES:
        raise ParameterError(
            f"a run of {steps} steps (max_time_s {params.max_time_s:g} / dt {params.dt:g}) "
            f"with {n_obstacles} obstacle(s) would record about {size / 2**30:.2f} GiB; "
            f"the limit is {MAX_RUN_BYTES / 2**30:.0f} GiB")


@dataclass(frozen=True)
class MovingObstacle:
    """An obstacle that follows its own polyline and then stays at its end.

    Attributes:
        path: (k, 2) waypoints in cells, k >= 1 (any array-like; stored as a
            read-only float array).
        speed: cells per second (paper: 1 u/s, like the AGV).
        start_time: it waits at ``path[0]`` until this time.
        name: a label for plots and events.
    """

    path: Any
    speed: float = 1.0
    start_time: float = 0.0
    name: str = ""

    def __post_init__(self) -> None:
        try:
            path = np.array(self.path, dtype=float).reshape(-1, 2)
        except (TypeError, ValueError, OverflowError):
            raise InputDataError(
                f"MovingObstacle.path must be a list of (x, y) points, got {self.path!r:.80}") \
                from None
        if path.shape[0] < 1 or not np.all(np.isfinite(path)):
            raise InputDataError(
                f"MovingObstacle.path must hold >= 1 finite (x, y) points, "
                f"got {self.path!r:.80}")
        path.setflags(write=False)
        object.__setattr__(self, "path", path)
        require_positive("MovingObstacle", "speed", self.speed)
        require_non_negative("MovingObstacle", "start_time", self.start_time)
        if not isinstance(self.name, str):
            raise InputDataError(f"MovingObstacle.name must be a string, got {self.name!r:.80}")

    def positions(self, times: np.ndarray) -> np.ndarray:
        """Positions (len(times), 2) at the given times."""
        times = np.asarray(times, dtype=float)
        if self.path.shape[0] == 1:
            return np.repeat(self.path, times.shape[0], axis=0)
        cum = _cumlen(self.path)
        s = np.clip((times - self.start_time) * self.speed, 0.0, cum[-1])
        return np.column_stack([np.interp(s, cum, self.path[:, 0]),
                                np.interp(s, cum, self.path[:, 1])])


@dataclass(frozen=True)
class AgvScenario:
    """A static map, the AGV's start and goal, and the moving obstacles.

    Attributes:
        states: the 2-bit local map (uint8 ``[y, x]``, values 0-3; see
            :mod:`.certainty_grid`); default: from the world's occupancy
            (no mixed cells). Start and goal must be ``00`` cells.
    """

    name: str
    world: GridWorld
    start: tuple[int, int]
    goal: tuple[int, int]
    obstacles: tuple[MovingObstacle, ...] = ()
    params: AgvParams = field(default_factory=AgvParams)
    description: str = ""
    states: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.world, GridWorld):
            raise InputDataError(f"AgvScenario.world must be a GridWorld, got {self.world!r:.80}")
        if self.states is None:
            states = states_of_occupancy(self.world.occupancy)
        else:
            states = np.asarray(self.states)
            if states.shape != self.world.occupancy.shape or not np.issubdtype(
                    states.dtype, np.integer) or states.min() < 0 or states.max() > 3:
                raise InputDataError(
                    f"AgvScenario.states must be integers 0-3 of shape "
                    f"{self.world.occupancy.shape}, got {states.dtype} {states.shape}")
            states = states.astype(np.uint8)
            if np.any((states >= 2) != self.world.occupancy):
                raise InputDataError("AgvScenario.states disagree with the world: states "
                                     "10/11 must be exactly its blocked cells")
        states.setflags(write=False)
        object.__setattr__(self, "states", states)
        object.__setattr__(self, "start", self.world.check_cell("start", self.start))
        object.__setattr__(self, "goal", self.world.check_cell("goal", self.goal))
        route_map = routing_map(states)
        for label in ("start", "goal"):
            x, y = getattr(self, label)
            if route_map[y, x]:
                raise UnreachableError(
                    f"{label} ({x}, {y}) is on a mixed (01) cell of the local map; only 00 "
                    f"cells are routable")
        obstacles = tuple(self.obstacles)
        for i, ob in enumerate(obstacles):
            if not isinstance(ob, MovingObstacle):
                raise InputDataError(f"AgvScenario.obstacles[{i}] must be a MovingObstacle, "
                                     f"got {ob!r:.80}")
            p = ob.path
            if np.any(p < -0.5) or np.any(p[:, 0] > self.world.width - 0.5) \
                    or np.any(p[:, 1] > self.world.height - 0.5):
                raise InputDataError(
                    f"AgvScenario.obstacles[{i}].path leaves the "
                    f"{self.world.width}x{self.world.height} map")
        object.__setattr__(self, "obstacles", obstacles)
        if not isinstance(self.params, AgvParams):
            raise ParameterError(f"AgvScenario.params must be AgvParams, got {self.params!r:.80}")
        check_run_size(self.params, len(obstacles))

    @property
    def routing_map(self) -> np.ndarray:
        """Bool ``[y, x]``: cells the AGV may not route through (not ``00``)."""
        assert self.states is not None
        return routing_map(self.states)

    def with_params(self, **changes: Any) -> AgvScenario:
        """A copy with some :class:`AgvParams` fields changed."""
        return replace(self, params=replace(self.params, **changes))


@dataclass(frozen=True)
class Event:
    """Something the AGV did or saw, at a simulation time."""

    time: float
    kind: str
    detail: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {"time": round(self.time, 6), "kind": self.kind, "detail": self.detail}


@dataclass(frozen=True)
class AgvRun:
    """The record of one simulated run.

    Attributes:
        scenario: name of the scenario.
        outcome: :class:`Outcome` ``success``, ``collision``, ``timeout`` or
            ``no_path`` (the goal cannot be reached on the static map).
        time_s: time at which the run ended.
        free_time_s: time of the same run without moving obstacles and drift.
        min_separation: smallest AGV-obstacle centre distance seen (inf if none).
        times: (T,) sample times; ``trajectory`` (T, 2) true AGV positions;
            ``believed`` (T, 2) where the AGV thought it was; ``speeds`` (T,);
            ``obstacle_positions`` (m, T, 2).
        events: what happened, in time order.
        planned_route: (k, 2) the route planned before the start.
        sections: the planned route's sections (rules 3-5).
        static_cells: bool ``[y, x]``: cells added to the AGV's map by obstacles
            that became static.
        seed: the drift seed (None: drift off or unseeded).
    """

    scenario: str
    outcome: Outcome
    time_s: float
    free_time_s: float
    min_separation: float
    times: np.ndarray
    trajectory: np.ndarray
    believed: np.ndarray
    speeds: np.ndarray
    obstacle_positions: np.ndarray
    events: tuple[Event, ...]
    planned_route: np.ndarray
    sections: tuple[Section, ...]
    static_cells: np.ndarray
    world: GridWorld
    params: AgvParams
    seed: int | None = None

    @property
    def success(self) -> bool:
        return self.outcome == Outcome.SUCCESS

    @property
    def delay_s(self) -> float:
        """Arrival time minus the obstacle-free time (``nan`` unless success)."""
        return self.time_s - self.free_time_s if self.success else float("nan")

    @property
    def path_length(self) -> float:
        return polyline_length(self.trajectory)

    @property
    def drift_error(self) -> np.ndarray:
        """(T,) distance between the true and the believed position."""
        d = self.trajectory - self.believed
        return np.hypot(d[:, 0], d[:, 1])

    @property
    def mean_drift_error(self) -> float:
        e = self.drift_error
        return float(e.mean()) if len(e) else 0.0

    @property
    def max_drift_error(self) -> float:
        e = self.drift_error
        return float(e.max()) if len(e) else 0.0

    def kinds(self) -> list[str]:
        """Event kinds in time order."""
        return [e.kind for e in self.events]

    def first(self, kind: str) -> Event | None:
        """The first event of a kind, or ``None``."""
        return next((e for e in self.events if e.kind == kind), None)

    def to_dict(self, *, trajectory: bool = True) -> dict[str, Any]:
        """JSON-safe record (inf/nan as None)."""
        out: dict[str, Any] = {
            "scenario": self.scenario, "outcome": self.outcome.value, "success": self.success,
            "time_s": self.time_s, "free_time_s": self.free_time_s,
            "delay_s": self.delay_s if self.success else None,
            "min_separation": self.min_separation if math.isfinite(self.min_separation)
            else None,
            "path_length": self.path_length,
            "mean_drift_error": self.mean_drift_error,
            "max_drift_error": self.max_drift_error,
            "seed": self.seed,
            "events": [e.to_dict() for e in self.events],
            "planned_route": self.planned_route.tolist(),
            "sections": [{"start": list(s.start), "end": list(s.end), "road": s.road,
                          "leaves": list(s.leaves), "leg": s.leg} for s in self.sections],
            "params": asdict(self.params),
        }
        if trajectory:
            out["times"] = self.times.tolist()
            out["trajectory"] = self.trajectory.tolist()
            out["believed"] = self.believed.tolist()
            out["obstacle_positions"] = self.obstacle_positions.tolist()
        return out

    def to_plan_result(self, runtime_s: float = 0.0) -> PlanResult:
        """The run as the planner protocol's :class:`PlanResult`: the driven
        path (simplified), the outcome, and a JSON-safe summary in ``info``."""
        info = self.to_dict(trajectory=False)
        for key in ("scenario", "outcome", "success"):
            info.pop(key)
        message = "ok" if self.success else next(
            (f"{e.kind}: {e.detail}" if e.detail else e.kind for e in reversed(self.events)
             if e.kind in ("collision", "timeout", "no_path")), self.outcome.value)
        path = (np.zeros((0, 2)) if self.outcome == Outcome.NO_PATH
                else simplify(self.trajectory, 0.05))
        return PlanResult(path, self.success, message, "agv", runtime_s, info=info,
                          outcome=self.outcome)

    def summary(self) -> str:
        counts: dict[str, int] = {}
        for e in self.events:
            counts[e.kind] = counts.get(e.kind, 0) + 1
        ev = ", ".join(f"{k} x{n}" for k, n in counts.items())
        delay = f"delay {self.delay_s:.2f} s, " if self.success else ""
        sep = (f"min separation {self.min_separation:.2f}"
               if math.isfinite(self.min_separation) else "no obstacle")
        drift = (f", drift error mean {self.mean_drift_error:.2f} / max "
                 f"{self.max_drift_error:.2f} cells" if self.params.drift else "")
        return (f"{self.scenario}: {self.outcome.value} at t = {self.time_s:.2f} s "
                f"(obstacle-free {self.free_time_s:.2f} s), {delay}{sep}, "
                f"path {self.path_length:.2f} cells{drift}; events: {ev}")


def plan_route(world: GridWorld, start: Any, goal: Any, params: AgvParams | None = None,
               *, states: np.ndarray | None = None) -> np.ndarray:
    """The planned route (k, 2), start first, of an AGV on a static map
    (routing only through ``00`` cells of ``states``, default: the world's
    occupancy).

    Raises:
        UnreachableError: start or goal outside the map or blocked.
        NoPathError: the goal cannot be reached.
    """
    params = AgvParams() if params is None else params
    s = world.check_cell("start", start)
    g = world.check_cell("goal", goal)
    occ = routing_map(states_of_occupancy(world.occupancy) if states is None else states)
    tree = build_tree(occ)
    subgoals = navigate(tree, occ, s, g, turn_weight=params.turn_weight,
                        clearance=params.wall_clearance)
    return np.vstack([np.array(s, dtype=float), subgoals])


def line_of_sight(occupancy: np.ndarray, a: Any, b: Any) -> bool:
    """Whether the segment a-b touches no blocked cell (closed squares).

    Between cell centres this is the grid family's exact kernel; any other
    end points go through a quadtree of ``occupancy`` (the same rule).
    """
    occ = np.asarray(occupancy, dtype=bool)
    pa, pb = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if np.all(pa == np.round(pa)) and np.all(pb == np.round(pb)):
        from subtask_opt.planners.grid._kernels import segment_hits

        return segment_hits(occ, int(pa[0]), int(pa[1]), int(pb[0]), int(pb[1]), True) == 0
    return build_tree(occ).segment_free(pa, pb)


_DETOUR_TAGS = ("rejoin", "back", "return")
"""Way points that are not route legs: back to the leg after a fix, and a back-off."""
_TRAIL_POINTS = 400
"""The AGV remembers this many of its last positions (the way back of a back-off)."""
_MAX_CORNERS_MEASURED = 8
"""A check point measures at most this many visible corners, nearest first."""
_MIN_FIX_ANGLE = math.radians(20.0)
"""Two corners fix the position only when their bearings differ by at least this."""


def _two_corner_fix(marks: np.ndarray, seen: list[tuple[int, float, float]],
                    pixel: float = 1e-3
                    ) -> tuple[np.ndarray, float, tuple[int, int], float, float] | None:
    """Position and heading from two measured corners (``seen``: corner
    index, bearing ``TH`` from the heading, distance ``X``), using the pair
    whose bearings are farthest from parallel; None when no pair is at least
    :data:`_MIN_FIX_ANGLE` apart.

    The position is where the circles of radius ``X`` about the two corners
    meet, on the side where corner j lies at the measured angle ``TH_j -
    TH_i`` from corner i (a difference of two bearings: the heading cancels).
    Returns (position, heading, the pair, the expected position error, the
    nearer distance): ``X`` is off by about ``X tan(TH)`` times the bearing
    quantisation ``pixel``, and the error of the intersection is those over
    the sine of the angle between the bearings.
    """
    best, pair = math.sin(_MIN_FIX_ANGLE), None
    for a in range(len(seen)):
        for b in range(a + 1, len(seen)):
            q = abs(math.sin(seen[b][1] - seen[a][1]))
            if q >= best:
                best, pair = q, (a, b)
    if pair is None:
        return None
    (i, th_i, x_i), (j, th_j, x_j) = seen[pair[0]], seen[pair[1]]
    mi, mj = marks[i], marks[j]
    u = mj - mi
    d = math.hypot(u[0], u[1])
    u = u / d
    along = (x_i * x_i - x_j * x_j + d * d) / (2 * d)
    across = math.sqrt(max(x_i * x_i - along * along, 0.0))
    sign = 1.0 if math.sin(th_j - th_i) > 0 else -1.0
    for side in (1.0, -1.0):
        pos = mi + along * u + side * across * np.array([-u[1], u[0]])
        a_i, a_j = mi - pos, mj - pos
        if (a_i[0] * a_j[1] - a_i[1] * a_j[0]) * sign >= 0:
            break
    heading_i = math.atan2(a_i[1], a_i[0]) - th_i
    heading_j = math.atan2(a_j[1], a_j[0]) - th_j
    heading = math.atan2(math.sin(heading_i) + math.sin(heading_j),
                         math.cos(heading_i) + math.cos(heading_j))
    err = pixel * (x_i * abs(math.tan(th_i)) + x_j * abs(math.tan(th_j)) + x_i + x_j) / best
    return pos, heading, (i, j), err, min(x_i, x_j)


def _swept_distance(r0: np.ndarray, r1: np.ndarray) -> np.ndarray:
    """Least norm of ``r0 + f (r1 - r0)`` over f in [0, 1], row by row: the
    closest approach of two points moving straight during one step (``r0``,
    ``r1``: obstacle minus AGV at its start and end)."""
    d = r1 - r0
    den = np.einsum("ij,ij->i", d, d)
    f = np.clip(-np.einsum("ij,ij->i", r0, d) / np.where(den > 0, den, 1.0), 0.0, 1.0)
    e = r0 + f[:, None] * d
    return np.hypot(e[:, 0], e[:, 1])


def _cumlen(pts: np.ndarray) -> np.ndarray:
    cum = np.zeros(pts.shape[0])
    if pts.shape[0] > 1:
        cum[1:] = np.cumsum(np.hypot(*np.diff(pts, axis=0).T))
    return cum


# -- simulation ---------------------------------------------------------------------------
class _Agv:
    """Mutable state of one run (private: :func:`simulate` is the API)."""

    def __init__(self, scenario: AgvScenario, route: np.ndarray, seed: int | None) -> None:
        self.sc = scenario
        self.p = p = scenario.params
        self.occ = scenario.routing_map.copy()
        self.tree: Quadtree = build_tree(self.occ)
        self.global_occ = np.asarray(scenario.world.occupancy, dtype=bool)
        self.static_cells = np.zeros_like(self.occ)
        self.pos = route[0].copy()          # where the AGV believes it is
        self.leg_start = route[0].copy()    # where the current leg began
        self.true = route[0].copy()         # where it is
        self.heading = math.atan2(*(route[-1] - route[0])[::-1]) if len(route) > 1 else 0.0
        self.v = 0.0
        self.wps: list[np.ndarray] = [r.copy() for r in route[1:]]
        self.tags: list[str] = ["subgoal"] * (len(self.wps) - 1) + ["goal"]
        self.events: list[Event] = []
        self.mode = "cruise"
        self.waiting = False
        self.priority: dict[int, str] = {}
        self.yielded: set[int] = set()  # obstacles the AGV gave way to after entering first
        self.trail: list[np.ndarray] = [route[0].copy()]  # believed positions driven, in order
        self.sidestepped: set[int] = set()
        self.static: set[int] = set()
        self.blocked_logged: set[int] = set()
        self.stand_time = np.zeros(len(scenario.obstacles))
        self.conflict = -1
        self.leg_checked = False
        # odometry drift
        self.rng = np.random.default_rng(seed) if p.drift else None
        self.bias = self.scale = self.walk = 0.0
        self.heading_fix = 0.0  # the heading error the AGV has measured and steers against
        # what the AGV believes of its own error (std of position, variance of heading)
        self.pos_sd = 0.0
        self.heading_var = math.radians(p.drift_heading_sd_deg) ** 2
        if self.rng is not None:
            self.bias = math.radians(float(self.rng.normal(0.0, p.drift_heading_sd_deg)))
            self.scale = float(self.rng.normal(0.0, p.drift_scale_sd))
        self.marks = (np.vstack([landmarks(self.global_occ), room_corners(self.global_occ)])
                      if p.drift and p.check_points else np.zeros((0, 2)))
        self.wall_tree = build_tree(self.global_occ)  # walls as they are (camera, collisions)
        self.next_check = p.check_interval_s

    def log(self, t: float, kind: str, detail: str = "") -> None:
        self.events.append(Event(float(t), kind, detail))

    def ahead(self) -> tuple[np.ndarray, np.ndarray]:
        pts = np.vstack([self.pos[None, :]] + [w[None, :] for w in self.wps])
        return pts, _cumlen(pts)

    def predict(self, pts: np.ndarray, cum: np.ndarray, v_target: float, obs: np.ndarray,
                vel: np.ndarray) -> tuple[float, int]:
        p = self.p
        motion = K.Motion(float(self.v), float(v_target), float(p.a_max), float(p.dt),
                          int(round(p.horizon_s / p.dt)))
        sep, j, _ = K.predict_min_separation(pts, cum, motion, obs, vel)
        return float(sep), int(j)

    # the quadtree check of the leg ahead ---------------------------------------------------
    def check_leg(self, t: float, obs: np.ndarray, ids: np.ndarray) -> None:
        """When a leg starts: is it still free in the AGV's map, and which seen
        obstacles stand in the leaves of its sections."""
        if not self.wps:
            return
        nxt = self.wps[0]
        if not self.tree.segment_free(self.pos, nxt):
            self.log(t, "section", f"leg to ({nxt[0]:.0f}, {nxt[1]:.0f}) is blocked in the "
                                   f"map: re-plan")
            self.replan(t, nxt)
            return
        secs = segment_route(np.array([self.pos, nxt]), self.tree, open_leaf=self.p.open_leaf)
        leaves = {lf for s in secs for lf in s.leaves}
        inside = [int(j) for j, o in zip(ids, obs, strict=True)
                  if self.tree.leaf_at(o) in leaves]
        if inside:
            self.log(t, "section", f"obstacle(s) {inside} in the next section(s) "
                                   f"({len(secs)} section(s), {len(leaves)} leaves)")

    # crossing priority -------------------------------------------------------------------
    def classify(self, pts: np.ndarray, cum: np.ndarray, o: np.ndarray, v: np.ndarray
                 ) -> tuple[str, np.ndarray | None, float]:
        """(kind, crossing point, its arc length on the path ahead)."""
        speed = math.hypot(v[0], v[1])
        if speed < 1e-9:
            return "stationary", None, math.nan
        for i in range(pts.shape[0] - 1):
            a, b = pts[i], pts[i + 1]
            d = b - a
            den = v[0] * (-d[1]) - v[1] * (-d[0])
            if abs(den) < 1e-12:
                continue
            r = a - o
            tau = (r[0] * (-d[1]) - r[1] * (-d[0])) / den
            sig = (v[0] * r[1] - v[1] * r[0]) / den
            if tau >= 0 and 0 <= sig <= 1:
                arc = cum[i] + sig * math.hypot(d[0], d[1])
                t_agv = arc / self.p.v_nominal
                if t_agv + self.p.priority_margin_s < tau:
                    kind = "agv_first"
                elif tau + self.p.priority_margin_s < t_agv:
                    kind = "obstacle_first"
                else:
                    kind = "simultaneous"
                return kind, a + sig * d, arc
        return "head_on", None, math.nan

    def sidestep(self, t: float, pts: np.ndarray, cum: np.ndarray, x_pt: np.ndarray,
                 arc: float, vel: np.ndarray, j: int) -> bool:
        """Pass behind obstacle ``j``: via a point on its track behind the
        crossing, then back onto the path ahead (recovery)."""
        p = self.p
        u = vel / math.hypot(vel[0], vel[1])
        side = np.round(x_pt - u * p.sidestep_offset)
        back_arc = min(arc + p.sidestep_offset, cum[-1])
        i = int(np.searchsorted(cum, back_arc, side="right"))
        rejoin = np.array(K.point_on_polyline(pts, cum, back_arc))
        h, w = self.occ.shape
        if not (0 <= side[0] < w and 0 <= side[1] < h) or self.occ[int(side[1]), int(side[0])]:
            return False
        c = p.wall_clearance
        if not (self.tree.segment_free(self.pos, side, c)
                and self.tree.segment_free(side, rejoin, c)):
            return False
        # pts[0] is the AGV and pts[i] is wps[i - 1]: keep what lies beyond the rejoin point
        if i >= pts.shape[0]:
            keep_w: list[np.ndarray] = []
            keep_t: list[str] = []
            tag_rejoin = "goal"
        else:
            keep_w, keep_t, tag_rejoin = self.wps[i - 1:], self.tags[i - 1:], "recovery"
        self.wps = [side, rejoin] + keep_w
        self.tags = ["sidestep", tag_rejoin] + keep_t
        self.leg_start = self.pos.copy()
        self.log(t, "sidestep", f"obstacle {j}: pass behind it via "
                                f"({side[0]:.0f}, {side[1]:.0f})")
        return True

    def decide(self, t: float, obs: np.ndarray, vel: np.ndarray, ids: np.ndarray) -> float:
        """Speed target of this step (rules 3-2, 3-3 and the crossing rules)."""
        p = self.p
        if len(ids) == 0:
            return self._set_mode(t, "cruise", p.v_nominal, -1)
        pts, cum = self.ahead()
        sep, jj = self.predict(pts, cum, p.v_nominal, obs, vel)
        if sep >= p.safety_distance:
            return self._set_mode(t, "cruise", p.v_nominal, -1)
        j = int(ids[jj])
        kind, x_pt, arc = self.classify(pts, cum, obs[jj], vel[jj])
        if self.priority.get(j) == "agv_first" and j not in self.yielded:
            kind = "agv_first"  # who enters first is decided once, while the AGV keeps it
        if self.priority.get(j) != kind:
            self.priority[j] = kind
            self.log(t, "crossing", f"obstacle {j}: {kind}")
        self.conflict = j
        order = [("brake", p.v_brake), ("stop", 0.0), ("speed_up", p.v_max)]
        if p.crossing_rules and kind == "agv_first":
            if p.speed_up_to_pass:
                order = [("speed_up", p.v_max), ("brake", p.v_brake), ("stop", 0.0)]
            elif sep >= p.pass_distance:  # rule 5-2-1: keep the normal speed
                return self._set_mode(t, "cruise", p.v_nominal, j)
        if p.crossing_rules and kind == "simultaneous" and j not in self.sidestepped \
                and x_pt is not None and not self.backing:
            self.sidestepped.add(j)
            saved = (self.wps, self.tags, len(self.events), self.leg_start)
            if self.sidestep(t, pts, cum, x_pt, arc, vel[jj], j):
                new_pts, new_cum = self.ahead()
                similar = min(p.v_max, max(p.v_brake, math.hypot(*vel[jj])))
                for mode, v_t in [("cruise", similar), *order]:
                    s, _ = self.predict(new_pts, new_cum, v_t, obs, vel)
                    if s >= p.safety_distance:
                        return self._set_mode(t, mode, v_t, j)
                # no clear way past on the far side either (other obstacles): keep the route
                self.wps, self.tags, self.leg_start = saved[0], saved[1], saved[3]
                del self.events[saved[2]:]
        best_mode, best_v, best_sep = "stop", 0.0, -math.inf
        for mode, v_t in order:
            s, _ = self.predict(pts, cum, v_t, obs, vel)
            if s >= p.safety_distance:
                best_mode, best_v, best_sep = mode, v_t, math.inf
                break
            if s > best_sep:
                best_mode, best_v, best_sep = mode, v_t, s
        # even the best choice ahead comes closer than the prediction can be trusted
        back = self.back_path() if best_sep < p.pass_distance else None
        if back is not None:
            s, _ = self.predict(back, _cumlen(back), p.v_brake, obs, vel)
            if s > best_sep:  # and backing off keeps more room
                self.wps = [*back[1:], *back[-2::-1]] + self.wps
                self.tags = ["back"] * (len(back) - 1) + ["return"] * (len(back) - 1) \
                    + self.tags
                best_mode, best_v = "back_off", p.v_brake
        if best_v < p.v_nominal and kind == "agv_first":
            self.yielded.add(j)  # it gives way after all: who enters first is open again
        return self._set_mode(t, best_mode, best_v, j)

    @property
    def backing(self) -> bool:
        """Whether the AGV is backing off or returning from it."""
        return bool(self.tags) and self.tags[0] in ("back", "return")

    def back_path(self) -> np.ndarray | None:
        """The way back (k, 2), from the AGV along the trail it drove, at most
        ``back_off`` long; None while backing or with less than half a cell."""
        if self.backing or self.p.back_off <= 0:
            return None
        pts, length = [self.pos], 0.0
        for q in reversed(self.trail):
            d = math.hypot(*(q - pts[-1]))
            if d <= 1e-9:
                continue
            if length + d >= self.p.back_off:
                pts.append(pts[-1] + (q - pts[-1]) * ((self.p.back_off - length) / d))
                length = self.p.back_off
                break
            pts.append(q)
            length += d
        return np.array(pts) if length >= 0.5 else None

    def _set_mode(self, t: float, mode: str, v_target: float, j: int) -> float:
        if mode != self.mode:
            who = f"obstacle {j}" if j >= 0 else ""
            if mode == "cruise":
                self.log(t, "resume", who)
            elif mode == "speed_up":
                self.log(t, "speed_up", f"{who}: pass first")
            elif mode == "back_off":
                self.log(t, "back_off", f"{who}: back off along the way it came")
            else:
                self.log(t, "brake", f"{who}: {'stop' if mode == 'stop' else 'slow down'}")
            self.mode = mode
        return v_target

    # static obstacles and recovery -------------------------------------------------------
    def make_static(self, t: float, j: int, at: np.ndarray) -> None:
        p = self.p
        h, w = self.occ.shape
        ys, xs = np.mgrid[0:h, 0:w]
        near = np.hypot(xs - at[0], ys - at[1]) <= p.static_radius
        me = (min(max(int(round(self.pos[1])), 0), h - 1),
              min(max(int(round(self.pos[0])), 0), w - 1))
        near[me] = False
        gx, gy = self.sc.goal
        if near[gy, gx]:
            if j not in self.blocked_logged:
                self.blocked_logged.add(j)
                self.log(t, "blocked", f"obstacle {j} stands on the goal "
                                       f"({gx}, {gy}): wait for it to leave")
            return
        saved = (self.occ.copy(), self.static_cells.copy(), self.tree)
        self.static_cells |= near & ~self.occ
        self.occ |= near
        self.tree = build_tree(self.occ)
        self.static.add(j)
        self.log(t, "static", f"obstacle {j} stood {p.static_after_s:g} s at "
                              f"({at[0]:.1f}, {at[1]:.1f})")
        if not self.replan(t, at):  # no way around: forget it, keep waiting for it to move
            self.occ, self.static_cells, self.tree = saved
            self.static.discard(j)

    def replan(self, t: float, at: np.ndarray) -> bool:
        """Detour around the new static cells to the first free point of the
        planned route beyond them, then the rest of the route; False when
        there is no way around."""
        p = self.p
        pts, cum = self.ahead()
        samples = np.arange(0.0, cum[-1] + 0.25, 0.25)
        xy = np.array([K.point_on_polyline(pts, cum, s) for s in samples])
        near = np.hypot(xy[:, 0] - at[0], xy[:, 1] - at[1])
        start = int(np.argmin(near))
        target, seg_end = None, len(pts) - 1
        h, w = self.occ.shape
        for k in range(start, len(samples)):
            c = np.clip(np.round(xy[k]), 0, [w - 1, h - 1])
            if near[k] < p.safety_distance + 0.5 or self.occ[int(c[1]), int(c[0])]:
                continue
            i = min(int(np.searchsorted(cum, samples[k], side="right")), len(pts) - 1)
            if self.tree.segment_free(c, pts[i], p.wall_clearance):
                target, seg_end = c, i
                break
        if target is None:
            target, seg_end = np.array(self.sc.goal, dtype=float), len(pts)
        try:
            detour = navigate(self.tree, self.occ, self.pos, target, turn_weight=p.turn_weight,
                              clearance=p.wall_clearance)
        except NoPathError as exc:
            self.log(t, "blocked", str(exc))
            return False
        rest = seg_end - 1  # index into wps of pts[seg_end]
        keep_w, keep_t = self.wps[rest:], self.tags[rest:]
        if seg_end >= len(pts) or (keep_w and np.allclose(keep_w[0], target)):
            keep_w, keep_t = keep_w[1:], keep_t[1:]
        last = "goal" if not keep_w else "recovery"
        self.wps = list(detour) + keep_w
        self.tags = ["subgoal"] * (len(detour) - 1) + [last] + keep_t
        self.leg_start = self.pos.copy()
        self.mode = "replan"
        self.leg_checked = True
        self.log(t, "replan", f"detour of {len(detour)} sub-goal(s), rejoin the route at "
                              f"({target[0]:.0f}, {target[1]:.0f})")
        return True

    # path following: check points against drift ------------------------------------------
    def check_point(self, t: float) -> None:
        """Measure the visible corners by eq. (3) and fix the position.

        With two corners in view at bearings far enough apart, the position
        is the point at their distances ``X`` (eq. (3)'s ``X`` does not depend
        on the heading) on the side their bearings ``TH`` say, and the
        bearings then give the true heading, which calibrates the odometry's
        heading error (:attr:`heading_fix`). That fix is taken when its
        expected error is below the one-corner fix's.

        With one corner, the nearest, eq. (3) places the AGV on the circle of
        radius ``X`` about it (exact) at the bearing ``heading + TH``, which
        is off by ``X`` times the heading error. Along that circle the fix is
        weighed against dead reckoning by their expected errors (a scalar
        Kalman gain): the AGV tracks its own position and heading uncertainty
        from its odometry's specification (the ``drift_*`` parameters), so a
        far corner seen with an uncalibrated heading does not throw it off.
        """
        p = self.p
        if len(self.marks) == 0:
            return
        near_r, far_r = p.sonar_range
        rel = self.marks - self.true
        dist = np.hypot(rel[:, 0], rel[:, 1])
        true_heading = self.heading + self.bias + self.walk - self.heading_fix
        half_fov = math.radians(p.camera_fov_deg) / 2
        seen: list[tuple[int, float, float]] = []  # (corner, TH, X)
        for i in np.argsort(dist, kind="stable"):
            r = float(dist[i])
            if r > far_r or len(seen) == _MAX_CORNERS_MEASURED:
                break
            if r < near_r:
                continue
            th_true = float(wrap_angle(math.atan2(rel[i, 1], rel[i, 0]) - true_heading))
            if abs(th_true) >= half_fov:
                continue
            seen_at = self.marks[i] - 0.05 * rel[i] / r
            if not self.wall_tree.segment_free(self.true, seen_at):
                continue
            # what the sensor reports: an image column and a depression angle
            theta_x = round(p.camera_f_px * math.tan(th_true))
            k_angle = math.atan2(p.camera_height * math.cos(th_true), r)
            # eq. (3)
            th = math.atan(theta_x / p.camera_f_px)
            seen.append((int(i), th, p.camera_height * math.cos(th) / math.tan(k_angle)))
        if not seen:
            return
        pixel = 0.5 / p.camera_f_px  # bearing quantisation (half a pixel), radians
        # one corner, the nearest: eq. (3), weighed against dead reckoning along the circle
        i, th, x_dist = seen[0]
        m = self.marks[i]
        est = m - x_dist * np.array([math.cos(self.heading + th), math.sin(self.heading + th)])
        back = self.pos - m  # dead reckoning's position, moved onto the circle |q - m| = X
        norm = math.hypot(back[0], back[1])
        ranged = m + back * (x_dist / norm) if norm > 1e-12 else est
        meas_var = x_dist * x_dist * (self.heading_var + pixel * pixel)
        prior_var = self.pos_sd * self.pos_sd
        gain = prior_var / (prior_var + meas_var) if prior_var + meas_var > 0 else 1.0
        q = ranged + gain * (est - ranged) - m
        est = m + q * (x_dist / max(math.hypot(q[0], q[1]), 1e-12))
        pos_sd = math.sqrt((1.0 - gain) * prior_var)
        what = (f"corner ({m[0]:.1f}, {m[1]:.1f}) at X = {x_dist:.2f}, TH = "
                f"{math.degrees(th):.1f} deg")
        turn = f" (weight {gain:.2f})"
        # two corners: position and heading, when that is the better fix
        fix = _two_corner_fix(self.marks, seen, pixel)
        if fix is not None and fix[3] < pos_sd:
            est, heading, (i, j), pos_sd, x_min = fix
            dh = float(wrap_angle(heading - self.heading))
            self.heading_fix = float(wrap_angle(self.heading_fix + dh))
            self.heading_var = (pos_sd / x_min) ** 2 + pixel * pixel
            what = (f"corners ({self.marks[i, 0]:.1f}, {self.marks[i, 1]:.1f}) and "
                    f"({self.marks[j, 0]:.1f}, {self.marks[j, 1]:.1f})")
            turn = f", heading by {math.degrees(dh):.1f} deg"
        self.pos_sd = pos_sd
        shift = est - self.pos
        self.pos = est
        self.log(t, "check_point", f"{what}: position corrected by "
                                   f"{math.hypot(shift[0], shift[1]):.2f}{turn}")
        # the way driven and a back-off's way points were believed positions too
        self.trail = [q + shift for q in self.trail]
        for k, tag in enumerate(self.tags):
            if tag not in ("back", "return"):
                break
            self.wps[k] = self.wps[k] + shift
        if not self.backing:
            self.rejoin_leg()

    def rejoin_leg(self) -> None:
        """Path following after a fix: the AGV now knows it is beside its leg
        (``leg_start`` -> the next sub-goal). Rather than head for the
        sub-goal from there (a line nobody planned), it steers back to the
        leg at the point ``track_lookahead`` ahead of its projection on it
        (a ``rejoin`` way point), so it drives the planned, wall-clear route
        and the look-ahead predicts the path it really takes."""
        while self.tags and self.tags[0] == "rejoin":
            self.wps.pop(0)
            self.tags.pop(0)
        if not self.wps:
            return
        a, b = self.leg_start, self.wps[0]
        ab = b - a
        length = math.hypot(ab[0], ab[1])
        rel = self.pos - a
        if length <= 1e-12 or abs(ab[0] * rel[1] - ab[1] * rel[0]) / length <= 1e-9:
            return
        s = (ab[0] * rel[0] + ab[1] * rel[1]) / length + self.p.track_lookahead
        if s < length:
            self.wps.insert(0, a + ab * (max(s, 0.0) / length))
            self.tags.insert(0, "rejoin")

    # motion --------------------------------------------------------------------------------
    def move(self, t: float, v_target: float) -> None:
        p = self.p
        if self.rng is not None:
            self.walk += math.radians(float(self.rng.normal(0.0, p.drift_walk_deg))) \
                * math.sqrt(p.dt)
            self.heading_var += math.radians(p.drift_walk_deg) ** 2 * p.dt
        if self.v < v_target:
            self.v = min(self.v + p.a_max * p.dt, v_target)
        else:
            self.v = max(self.v - p.a_max * p.dt, v_target)
        if self.v <= 1e-12:
            if not self.waiting and self.mode == "stop":
                self.waiting = True
                self.log(t, "wait", f"obstacle {self.conflict} in the way")
            return
        self.waiting = False
        step = self.v * p.dt
        start = self.pos.copy()
        forward = not self.backing
        while step > 0 and self.wps:
            d = self.wps[0] - self.pos
            dist = math.hypot(d[0], d[1])
            if dist <= step:
                self.pos = self.wps.pop(0)
                tag = self.tags.pop(0)
                step -= dist
                if tag not in _DETOUR_TAGS:  # rejoin, back, return: the leg goes on
                    self.leg_start = self.pos.copy()
                    self.leg_checked = False
                frac = 1.0 - step / (self.v * p.dt)
                if tag in ("subgoal", "sidestep", "recovery"):
                    detail = f"({self.pos[0]:.0f}, {self.pos[1]:.0f})"
                    self.log(t + frac * p.dt, tag if tag == "recovery" else "subgoal", detail)
            else:
                self.pos = self.pos + d * (step / dist)
                step = 0.0
        moved = self.pos - start
        if moved[0] or moved[1]:
            self.heading = math.atan2(moved[1], moved[0])
            if forward:
                self.trail.append(self.pos.copy())
                del self.trail[:-_TRAIL_POINTS]
        if self.rng is None:
            self.true = self.pos.copy()
        else:
            a = self.bias + self.walk - self.heading_fix
            c, s = math.cos(a), math.sin(a)
            k = 1.0 + self.scale
            self.true = self.true + k * np.array([c * moved[0] - s * moved[1],
                                                  s * moved[0] + c * moved[1]])
            self.pos_sd += math.hypot(moved[0], moved[1]) * math.sqrt(
                self.heading_var + p.drift_scale_sd ** 2)

    def hit_wall(self, before: np.ndarray) -> bool:
        """Whether the true motion of the last step, ``before`` -> ``true``
        (a straight chord: :meth:`move` turns the whole step at once), touches
        a blocked cell's closed square or leaves the map."""
        return not self.wall_tree.segment_free(before, self.true)


def simulate(scenario: AgvScenario, *, seed: int | None = None,
             free_time: float | None = None) -> AgvRun:
    """Run a scenario to success, collision, timeout or ``no_path``.

    ``seed`` drives the odometry drift (used only with ``params.drift``).
    ``free_time`` is the obstacle-free arrival time if already known (it is
    otherwise measured by a second run without the moving obstacles and
    without drift).
    """
    seed = check_seed(seed, owner="simulate.seed")
    if not isinstance(scenario, AgvScenario):
        raise ParameterError(f"simulate needs an AgvScenario, got {type(scenario).__name__}")
    p = scenario.params
    check_run_size(p, len(scenario.obstacles))
    try:
        route = plan_route(scenario.world, scenario.start, scenario.goal, p,
                           states=scenario.states)
    except NoPathError as exc:
        return _no_path_run(scenario, str(exc), seed)
    sections = tuple(segment_route(route, build_tree(scenario.routing_map),
                                   open_leaf=p.open_leaf))
    if free_time is None:
        free_time = (simulate(replace(scenario, obstacles=(), params=replace(p, drift=False)),
                              free_time=0.0).time_s
                     if scenario.obstacles or p.drift else None)
    agv = _Agv(scenario, route, seed)
    n_steps = int(math.ceil(p.max_time_s / p.dt))
    times = np.arange(n_steps + 1) * p.dt
    m = len(scenario.obstacles)
    obs_traj = (np.stack([ob.positions(times) for ob in scenario.obstacles])
                if m else np.zeros((0, n_steps + 1, 2)))
    traj = np.zeros((n_steps + 1, 2))
    believed = np.zeros((n_steps + 1, 2))
    speeds = np.zeros(n_steps + 1)
    min_sep = math.inf
    outcome = Outcome.TIMEOUT
    far_r = p.sonar_range[1]
    k = 0
    for k in range(n_steps + 1):
        t = times[k]
        traj[k], believed[k], speeds[k] = agv.true, agv.pos, agv.v
        now = obs_traj[:, k]
        dist = np.hypot(now[:, 0] - agv.true[0], now[:, 1] - agv.true[1]) if m else np.zeros(0)
        if m:
            # closest approach during the last step, not only at its end
            swept = (_swept_distance(obs_traj[:, k - 1] - traj[k - 1], now - agv.true)
                     if k else dist)
            min_sep = min(min_sep, float(swept.min()))
            if swept.min() < p.collision_distance:
                outcome = Outcome.COLLISION
                agv.log(t, "collision", f"obstacle {int(swept.argmin())} at distance "
                                        f"{swept.min():.2f}")
                break
        if agv.hit_wall(traj[k - 1] if k else agv.true):
            outcome = Outcome.COLLISION
            agv.log(t, "collision", f"static obstacle at ({agv.true[0]:.2f}, "
                                    f"{agv.true[1]:.2f}) (drift)")
            break
        if not agv.wps:
            outcome = Outcome.SUCCESS
            agv.log(t, "goal")
            break
        if k == n_steps:
            agv.log(t, "timeout", f"not at the goal after {p.max_time_s:g} s")
            break
        if agv.rng is not None and p.check_points and t >= agv.next_check - 1e-9:
            agv.next_check += p.check_interval_s
            agv.check_point(t)
        # what the sonar sees, placed where the AGV believes it is
        seen = now - (agv.true - agv.pos)
        vel = (now - obs_traj[:, k - 1]) / p.dt if k else np.zeros_like(now)
        moving = np.hypot(vel[:, 0], vel[:, 1]) > 1e-9
        # the sonar's near limit applies to check points: an obstacle that comes
        # closer than it stays tracked (it was seen on its way in)
        in_range = dist <= far_r
        if not agv.leg_checked:
            agv.leg_checked = True
            ids_all = np.flatnonzero(in_range)
            agv.check_leg(t, seen[ids_all], ids_all)
        v_target = p.v_nominal
        if p.collision_check and m:
            for j in list(agv.static):
                if moving[j]:
                    agv.static.discard(j)
            ids = np.flatnonzero(in_range & ~np.isin(np.arange(m), list(agv.static)))
            agv.conflict = -1
            v_target = agv.decide(t, seen[ids], vel[ids], ids)
            j = agv.conflict
            for i in range(m):
                if i == j and agv.v <= 1e-12 and agv.mode == "stop" and not moving[i]:
                    agv.stand_time[i] += p.dt
                else:
                    agv.stand_time[i] = 0.0
            if j >= 0 and agv.stand_time[j] >= p.static_after_s - 1e-9:
                agv.stand_time[j] = 0.0
                agv.make_static(t, j, seen[j])
                v_target = 0.0
        agv.move(t, v_target)
    n = k + 1
    return AgvRun(
        scenario=scenario.name, outcome=outcome, time_s=float(times[k]),
        free_time_s=float(times[k]) if free_time is None else float(free_time),
        min_separation=min_sep, times=times[:n].copy(), trajectory=traj[:n].copy(),
        believed=believed[:n].copy(), speeds=speeds[:n].copy(),
        obstacle_positions=obs_traj[:, :n].copy(), events=tuple(agv.events),
        planned_route=route, sections=sections, static_cells=agv.static_cells,
        world=scenario.world, params=p, seed=seed)


def _no_path_run(scenario: AgvScenario, reason: str, seed: int | None) -> AgvRun:
    start = np.array([scenario.start], dtype=float)
    return AgvRun(
        scenario=scenario.name, outcome=Outcome.NO_PATH, time_s=0.0, free_time_s=math.nan,
        min_separation=math.inf, times=np.zeros(1), trajectory=start, believed=start.copy(),
        speeds=np.zeros(1), obstacle_positions=np.zeros((len(scenario.obstacles), 1, 2)),
        events=(Event(0.0, "no_path", reason),), planned_route=start, sections=(),
        static_cells=np.zeros(scenario.world.occupancy.shape, dtype=bool),
        world=scenario.world, params=scenario.params, seed=seed)


@register("agv", "agv", stochastic=True,
          description="AGV of seed 004 among moving obstacles: corner sub-goals on the 2-bit "
                      "local map, quadtree leg check, t-second collision check, crossing "
                      "rules, recovery, corner check points against drift")
def plan(world: GridWorld | AgvScenario, start: Any, goal: Any, *,
         params: AgvParams | None = None, seed: int | None = None,
         stop: Any = None) -> PlanResult:
    """Simulate the AGV from ``start`` to ``goal`` (the planner protocol).

    ``world`` is a :class:`GridWorld` (static map, no moving obstacles) or an
    :class:`AgvScenario` (its obstacles and local map are used; ``start``,
    ``goal`` and a given ``params`` replace its own). ``seed`` drives the
    odometry drift; ``stop`` must be None (the run ends by ``max_time_s``).
    The result's path is the driven trajectory (simplified); ``outcome`` is
    success, collision, timeout or no_path; ``info`` holds the run's summary
    and events.
    """
    import time

    seed = check_seed(seed)
    if stop is not None:
        raise ParameterError(f"the agv planner is not iterative: stop must be None, "
                             f"got {stop!r:.80}")
    if params is not None and not isinstance(params, AgvParams):
        raise ParameterError(f"agv.plan params must be AgvParams, got {params!r:.80}")
    if isinstance(world, AgvScenario):
        sc = replace(world, start=start, goal=goal,
                     params=world.params if params is None else params)
    elif isinstance(world, GridWorld):
        sc = AgvScenario(world.name or "plan", world, start, goal, (),
                         AgvParams() if params is None else params)
    else:
        raise ParameterError(f"agv.plan needs a GridWorld or an AgvScenario, "
                             f"got {type(world).__name__}")
    t0 = time.perf_counter()
    run = simulate(sc, seed=seed)
    return run.to_plan_result(time.perf_counter() - t0)
