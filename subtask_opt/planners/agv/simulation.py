"""AGV among moving obstacles (seed 004): corner sub-goals, the t-second
collision check, crossing rules and path recovery, as a fixed-step simulation.

Geometry is in cells of the global map (x = column, y = row, a cell centre at
integer coordinates); time in seconds. The AGV and the obstacles are discs
moving at 1 cell/s by default, like the paper's 1 u/s.

**Corner detection (rules 2-1 ... 2-7).** The OCR'd rules test whether an
obstacle cell and its two opposite neighbours along one of four lines
(vertical, horizontal, two diagonals) are all obstacle; if none of the four
lines is, the cell is an *edge* (a convex corner). The AGV never drives to the
corner cell itself: its *near points* are the free diagonal neighbours
outside the corner whose two side cells are free too.

**Navigation (rules 3-1 ... 3-4).** From the current point: if the goal is in
line of sight go straight to it (3-1); otherwise give each visible near point
the value ``distance + cost-to-go + turn_weight * |turn angle|`` and head for
the best one (the paper's "nearest corner with the smallest angle"; the
cost-to-go from the octile distance transform is what makes the choice
complete - the bare greedy rule can cycle) and repeat from it (3-4). Only near
points with a smaller cost-to-go than the current point count, so the route is
finite. The list of chosen sub-goals is the AGV's *planned route*.

**t-second collision check (rule 3-3).** Every step, each obstacle within
sensor range gets the velocity of its last two positions; the AGV's motion
along its own path ahead at a candidate speed and the obstacles' straight
extrapolations are stepped forward for ``horizon_s`` (the time factor); the
candidate is safe when the predicted distance never falls below
``safety_distance`` (the distance factor). Candidates: keep cruising; brake to
half speed; stop; speed up (the paper tries BRAKE first, then SPEED_UP).

**Crossing rules.** The first point where an obstacle's extrapolated ray meets
the AGV's path decides who enters first: AGV first -> keep speed, or speed up
to pass; obstacle first -> brake or wait (yield); both at once (arrival times
within ``priority_margin_s``) -> a sidestep through a near point behind the
obstacle's track ("the corner opposite the obstacle") at the obstacle's speed,
then back onto the planned route. An obstacle that stands still in front of
the waiting AGV for ``static_after_s`` (~10 s) becomes static: its cells enter
the AGV's map, the AGV re-plans to the first point of its planned route past
the obstacle (near points of the new map as sub-goals) and then follows the
rest of that route (recovery). This stands for step 2 of the paper's recovery
algorithm (compare the obstacle's time O(t) with the AGV's U(t)): while the
obstacle moves the AGV keeps its route and lets the check make it yield; once
the obstacle has stood still long enough, the near-point detour is taken.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, NoPathError, ParameterError, require_positive
from subtask_opt.base.results import polyline_length
from subtask_opt.planners.agv import _kernels as K
from subtask_opt.planners.grid.world import GridWorld

OUTCOMES = ("success", "collision", "timeout")
EVENT_KINDS = ("subgoal", "crossing", "brake", "wait", "speed_up", "resume", "sidestep",
               "static", "replan", "recovery", "blocked", "goal", "collision", "timeout")


# -- parameters and inputs ---------------------------------------------------------------
@dataclass(frozen=True)
class AgvParams:
    """Tuning of the AGV simulation (cells, seconds).

    Attributes:
        dt: simulation time step.
        v_nominal: cruising speed (paper: 1 cell/s).
        v_max: speed when speeding up to pass.
        v_brake: speed when braking to yield.
        a_max: acceleration limit (speed changes by at most ``a_max * dt`` a step).
        horizon_s: time factor of the t-second check (how far ahead it looks).
        safety_distance: distance factor: a prediction closer than this is a conflict.
        collision_distance: centres closer than this collide (sum of body radii).
        sensor_range: obstacles farther than this are not seen (sonar range).
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
    """

    dt: float = 0.25
    v_nominal: float = 1.0
    v_max: float = 1.5
    v_brake: float = 0.5
    a_max: float = 2.0
    horizon_s: float = 4.0
    safety_distance: float = 1.5
    collision_distance: float = 0.8
    sensor_range: float = 10.0
    static_after_s: float = 10.0
    static_radius: float = 1.5
    priority_margin_s: float = 1.0
    sidestep_offset: float = 2.0
    turn_weight: float = 1.0
    max_time_s: float = 300.0
    collision_check: bool = True
    crossing_rules: bool = True

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.type in ("bool", bool):
                if not isinstance(value, bool):
                    raise ParameterError(f"AgvParams.{f.name} must be a bool, got {value!r}")
            elif f.name == "turn_weight":
                if isinstance(value, bool) or not isinstance(value, (int, float)) \
                        or not math.isfinite(value) or value < 0:
                    raise ParameterError(
                        f"AgvParams.turn_weight must be a finite number >= 0, got {value!r}")
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
        if self.horizon_s < self.dt or self.max_time_s < self.dt:
            raise ParameterError(
                f"AgvParams.horizon_s and max_time_s must be >= dt ({self.dt!r}), got "
                f"{self.horizon_s!r} and {self.max_time_s!r}")

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> AgvParams:
        """Build from a mapping; unknown keys are an error naming them."""
        if not isinstance(data, dict):
            raise InputDataError(f"AGV params must be a mapping, got {data!r}")
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise ParameterError(
                f"unknown AgvParams field(s) {unknown}; allowed: {sorted(names)}")
        return cls(**data)


@dataclass(frozen=True)
class MovingObstacle:
    """An obstacle that follows its own polyline and then stays at its end.

    Attributes:
        path: (k, 2) waypoints in cells, k >= 1.
        speed: cells per second (paper: 1, like the AGV).
        start_time: it waits at ``path[0]`` until this time.
        name: a label for plots and events.
    """

    path: np.ndarray
    speed: float = 1.0
    start_time: float = 0.0
    name: str = ""

    def __post_init__(self) -> None:
        try:
            path = np.array(self.path, dtype=float).reshape(-1, 2)
        except (TypeError, ValueError):
            raise InputDataError(
                f"MovingObstacle.path must be a list of (x, y) points, got {self.path!r}") \
                from None
        if path.shape[0] < 1 or not np.all(np.isfinite(path)):
            raise InputDataError(
                f"MovingObstacle.path must hold >= 1 finite (x, y) points, got {self.path!r}")
        path.setflags(write=False)
        object.__setattr__(self, "path", path)
        require_positive("MovingObstacle", "speed", self.speed)
        if isinstance(self.start_time, bool) or not isinstance(self.start_time, (int, float)) \
                or not math.isfinite(self.start_time) or self.start_time < 0:
            raise ParameterError(
                f"MovingObstacle.start_time must be a finite number >= 0, "
                f"got {self.start_time!r}")

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
    """A static map, the AGV's start and goal, and the moving obstacles."""

    name: str
    world: GridWorld
    start: tuple[int, int]
    goal: tuple[int, int]
    obstacles: tuple[MovingObstacle, ...] = ()
    params: AgvParams = field(default_factory=AgvParams)
    description: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.world, GridWorld):
            raise InputDataError(f"AgvScenario.world must be a GridWorld, got {self.world!r}")
        object.__setattr__(self, "start", self.world.check_cell("start", self.start))
        object.__setattr__(self, "goal", self.world.check_cell("goal", self.goal))
        obstacles = tuple(self.obstacles)
        for i, ob in enumerate(obstacles):
            if not isinstance(ob, MovingObstacle):
                raise InputDataError(f"AgvScenario.obstacles[{i}] must be a MovingObstacle, "
                                     f"got {ob!r}")
            p = ob.path
            if np.any(p < -0.5) or np.any(p[:, 0] > self.world.width - 0.5) \
                    or np.any(p[:, 1] > self.world.height - 0.5):
                raise InputDataError(
                    f"AgvScenario.obstacles[{i}].path leaves the "
                    f"{self.world.width}x{self.world.height} map")
        object.__setattr__(self, "obstacles", obstacles)
        if not isinstance(self.params, AgvParams):
            raise ParameterError(f"AgvScenario.params must be AgvParams, got {self.params!r}")

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
        outcome: ``"success"``, ``"collision"`` or ``"timeout"``.
        time_s: time at which the run ended.
        free_time_s: time of the same run without moving obstacles.
        min_separation: smallest AGV-obstacle centre distance seen (inf if none).
        times: (T,) sample times; ``trajectory`` (T, 2) AGV positions;
            ``speeds`` (T,); ``obstacle_positions`` (m, T, 2).
        events: what happened, in time order.
        planned_route: (k, 2) the route planned before the start.
        static_cells: bool ``[y, x]``: cells added to the AGV's map by obstacles
            that became static.
    """

    scenario: str
    outcome: str
    time_s: float
    free_time_s: float
    min_separation: float
    times: np.ndarray
    trajectory: np.ndarray
    speeds: np.ndarray
    obstacle_positions: np.ndarray
    events: tuple[Event, ...]
    planned_route: np.ndarray
    static_cells: np.ndarray
    world: GridWorld
    params: AgvParams

    @property
    def success(self) -> bool:
        return self.outcome == "success"

    @property
    def delay_s(self) -> float:
        """Arrival time minus the obstacle-free time (``nan`` unless success)."""
        return self.time_s - self.free_time_s if self.success else float("nan")

    @property
    def path_length(self) -> float:
        return polyline_length(self.trajectory)

    def kinds(self) -> list[str]:
        """Event kinds in time order."""
        return [e.kind for e in self.events]

    def first(self, kind: str) -> Event | None:
        """The first event of a kind, or ``None``."""
        return next((e for e in self.events if e.kind == kind), None)

    def to_dict(self, *, trajectory: bool = True) -> dict[str, Any]:
        out: dict[str, Any] = {
            "scenario": self.scenario, "outcome": self.outcome, "success": self.success,
            "time_s": self.time_s, "free_time_s": self.free_time_s,
            "delay_s": self.delay_s if self.success else None,
            "min_separation": self.min_separation if math.isfinite(self.min_separation)
            else None,
            "path_length": self.path_length,
            "events": [e.to_dict() for e in self.events],
            "planned_route": self.planned_route.tolist(),
            "params": asdict(self.params),
        }
        if trajectory:
            out["times"] = self.times.tolist()
            out["trajectory"] = self.trajectory.tolist()
            out["obstacle_positions"] = self.obstacle_positions.tolist()
        return out

    def summary(self) -> str:
        counts: dict[str, int] = {}
        for e in self.events:
            counts[e.kind] = counts.get(e.kind, 0) + 1
        ev = ", ".join(f"{k} x{n}" for k, n in counts.items())
        delay = f"delay {self.delay_s:.2f} s, " if self.success else ""
        sep = (f"min separation {self.min_separation:.2f}"
               if math.isfinite(self.min_separation) else "no obstacle")
        return (f"{self.scenario}: {self.outcome} at t = {self.time_s:.2f} s "
                f"(obstacle-free {self.free_time_s:.2f} s), {delay}{sep}, "
                f"path {self.path_length:.2f} cells; events: {ev}")


# -- corners and navigation ---------------------------------------------------------------
def detect_corners(occupancy: np.ndarray) -> np.ndarray:
    """Obstacle cells that are edges by rules 2-2 ... 2-6 (bool ``[y, x]``).

    A blocked cell is *not* an edge when, along one of the four lines through
    it, both opposite neighbours are blocked too; the map border counts as
    free so that obstacles touching it keep their corners.
    """
    occ = np.asarray(occupancy, dtype=bool)
    p = np.pad(occ, 1, constant_values=False)
    h, w = occ.shape

    def nb(dy: int, dx: int) -> np.ndarray:
        return p[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]

    inline = ((nb(-1, 0) & nb(1, 0)) | (nb(0, -1) & nb(0, 1))
              | (nb(-1, -1) & nb(1, 1)) | (nb(-1, 1) & nb(1, -1)))
    return occ & ~inline


def near_points(occupancy: np.ndarray, corners: np.ndarray | None = None) -> np.ndarray:
    """Sub-goal points (k, 2) as cell centres (x, y): the free diagonal
    neighbours of edge cells whose two side cells are free."""
    occ = np.asarray(occupancy, dtype=bool)
    corners = detect_corners(occ) if corners is None else corners
    h, w = occ.shape
    free = np.pad(~occ, 1, constant_values=False)
    found = np.zeros((h, w), dtype=bool)
    cy, cx = np.nonzero(corners)
    for dy in (-1, 1):
        for dx in (-1, 1):
            ok = free[1 + cy + dy, 1 + cx + dx] & free[1 + cy + dy, 1 + cx] \
                & free[1 + cy, 1 + cx + dx]
            found[cy[ok] + dy, cx[ok] + dx] = True
    ys, xs = np.nonzero(found)
    return np.column_stack([xs, ys]).astype(float)


def line_of_sight(occupancy: np.ndarray, a: Any, b: Any) -> bool:
    """Whether the segment a-b touches no blocked cell (closed cells)."""
    return bool(K.segment_free(np.asarray(occupancy, dtype=bool), float(a[0]), float(a[1]),
                               float(b[0]), float(b[1])))


def navigate(occupancy: np.ndarray, start: Any, target: Any, *,
             turn_weight: float = 1.0, points: np.ndarray | None = None) -> np.ndarray:
    """Sub-goals (k, 2) from ``start`` to ``target`` by rules 3-1 ... 3-4.

    ``start`` may be any point of a free cell; ``target`` is a free cell
    centre. The last row is ``target``. ``points`` overrides the near points.

    Raises:
        NoPathError: the target cannot be reached on this map.
    """
    from subtask_opt.planners.grid.distance_transform import distance_field, path_from_field

    occ = np.asarray(occupancy, dtype=bool)
    world = GridWorld(occ)
    pos = np.array(start, dtype=float)
    tgt = np.array(target, dtype=float)
    tcell = (int(round(tgt[0])), int(round(tgt[1])))
    cost = distance_field(world, tcell, "octile")
    pts = near_points(occ) if points is None else np.asarray(points, dtype=float)
    pcost = cost[pts[:, 1].astype(int), pts[:, 0].astype(int)] if len(pts) else np.zeros(0)
    heading = tgt - pos
    out: list[np.ndarray] = []
    for _ in range(len(pts) + occ.size + 2):
        if K.segment_free(occ, pos[0], pos[1], tgt[0], tgt[1]):  # rule 3-1
            out.append(tgt)
            return np.array(out)
        cell = (int(round(pos[0])), int(round(pos[1])))
        here = cost[cell[1], cell[0]]
        if not math.isfinite(here):
            raise NoPathError(f"no route from ({pos[0]:.2f}, {pos[1]:.2f}) to target {tcell}")
        best, best_val = None, math.inf
        for i in np.flatnonzero(pcost < here - 1e-9):
            c = pts[i]
            if not K.segment_free(occ, pos[0], pos[1], c[0], c[1]):
                continue
            d = c - pos
            dist = math.hypot(d[0], d[1])
            val = dist + pcost[i] + turn_weight * _angle(heading, d)
            if val < best_val:
                best, best_val = c, val
        if best is None:
            # no visible near point leads closer: follow the distance transform
            cells = path_from_field(world, cost, cell).astype(float)
            best = cells[1] if len(cells) > 1 else cells[0]
            for c in cells[:0:-1]:
                if K.segment_free(occ, pos[0], pos[1], c[0], c[1]):
                    best = c
                    break
        heading = best - pos
        out.append(best.copy())
        pos = best.copy()
    raise NoPathError(f"navigation to {tcell} did not converge")  # pragma: no cover


def _angle(u: np.ndarray, v: np.ndarray) -> float:
    nu, nv = math.hypot(u[0], u[1]), math.hypot(v[0], v[1])
    if nu == 0 or nv == 0:
        return 0.0
    return math.acos(max(-1.0, min(1.0, float(u @ v) / (nu * nv))))


def plan_route(world: GridWorld, start: Any, goal: Any, params: AgvParams | None = None
               ) -> np.ndarray:
    """The planned route (k, 2), start first, of an AGV on a static map.

    Raises:
        UnreachableError: start or goal outside the map or blocked.
        NoPathError: the goal cannot be reached.
    """
    params = AgvParams() if params is None else params
    s = world.check_cell("start", start)
    g = world.check_cell("goal", goal)
    subgoals = navigate(world.occupancy, s, g, turn_weight=params.turn_weight)
    return np.vstack([np.array(s, dtype=float), subgoals])


def _cumlen(pts: np.ndarray) -> np.ndarray:
    cum = np.zeros(pts.shape[0])
    if pts.shape[0] > 1:
        cum[1:] = np.cumsum(np.hypot(*np.diff(pts, axis=0).T))
    return cum


# -- simulation ---------------------------------------------------------------------------
class _Agv:
    """Mutable state of one run (private: :func:`simulate` is the API)."""

    def __init__(self, scenario: AgvScenario, route: np.ndarray) -> None:
        self.sc = scenario
        self.p = scenario.params
        self.occ = np.array(scenario.world.occupancy, dtype=bool)
        self.static_cells = np.zeros_like(self.occ)
        self.pos = route[0].copy()
        self.v = 0.0
        self.wps: list[np.ndarray] = [r.copy() for r in route[1:]]
        self.tags: list[str] = ["subgoal"] * (len(self.wps) - 1) + ["goal"]
        self.events: list[Event] = []
        self.mode = "cruise"
        self.waiting = False
        self.seen: set[int] = set()
        self.sidestepped: set[int] = set()
        self.static: set[int] = set()
        self.stand_time = np.zeros(len(scenario.obstacles))
        self.conflict = -1

    def log(self, t: float, kind: str, detail: str = "") -> None:
        self.events.append(Event(float(t), kind, detail))

    def ahead(self) -> tuple[np.ndarray, np.ndarray]:
        pts = np.vstack([self.pos[None, :]] + [w[None, :] for w in self.wps])
        return pts, _cumlen(pts)

    def predict(self, pts, cum, v_target, obs, vel) -> tuple[float, int]:
        p = self.p
        steps = int(round(p.horizon_s / p.dt))
        sep, j, _ = K.predict_min_separation(pts, cum, self.v, v_target, p.a_max, p.dt,
                                             steps, obs, vel)
        return sep, j

    # crossing priority -------------------------------------------------------------------
    def classify(self, pts, cum, o, v) -> tuple[str, np.ndarray | None, float]:
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

    def sidestep(self, t, pts, cum, x_pt, arc, vel, j) -> bool:
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
        if not (line_of_sight(self.occ, self.pos, side) and line_of_sight(self.occ, side, rejoin)):
            return False
        # pts[0] is the AGV and pts[i] is wps[i - 1]: keep what lies beyond the rejoin point
        if i >= pts.shape[0]:
            keep_w, keep_t, tag_rejoin = [], [], "goal"
        else:
            keep_w, keep_t, tag_rejoin = self.wps[i - 1:], self.tags[i - 1:], "recovery"
        self.wps = [side, rejoin] + keep_w
        self.tags = ["sidestep", tag_rejoin] + keep_t
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
        if j not in self.seen:
            self.seen.add(j)
            self.log(t, "crossing", f"obstacle {j}: {kind}")
        self.conflict = j
        if p.crossing_rules and kind == "agv_first":
            order = [("speed_up", p.v_max), ("brake", p.v_brake), ("stop", 0.0)]
        else:
            order = [("brake", p.v_brake), ("stop", 0.0), ("speed_up", p.v_max)]
        if p.crossing_rules and kind == "simultaneous" and j not in self.sidestepped:
            self.sidestepped.add(j)
            saved = (self.wps, self.tags, len(self.events))
            if self.sidestep(t, pts, cum, x_pt, arc, vel[jj], j):
                new_pts, new_cum = self.ahead()
                similar = min(p.v_max, max(p.v_brake, math.hypot(*vel[jj])))
                for mode, v_t in [("cruise", similar)] + order:
                    s, _ = self.predict(new_pts, new_cum, v_t, obs, vel)
                    if s >= p.safety_distance:
                        return self._set_mode(t, mode, v_t, j)
                # no clear way past on the far side either (other obstacles): keep the route
                self.wps, self.tags = saved[0], saved[1]
                del self.events[saved[2]:]
        best_mode, best_v, best_sep = "stop", 0.0, -math.inf
        for mode, v_t in order:
            s, _ = self.predict(pts, cum, v_t, obs, vel)
            if s >= p.safety_distance:
                return self._set_mode(t, mode, v_t, j)
            if s > best_sep:
                best_mode, best_v, best_sep = mode, v_t, s
        return self._set_mode(t, best_mode, best_v, j)

    def _set_mode(self, t: float, mode: str, v_target: float, j: int) -> float:
        if mode != self.mode:
            who = f"obstacle {j}" if j >= 0 else ""
            if mode == "cruise":
                self.log(t, "resume", who)
            elif mode == "speed_up":
                self.log(t, "speed_up", f"{who}: pass first")
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
        me = (int(round(self.pos[1])), int(round(self.pos[0])))
        near[me] = False
        self.static_cells |= near & ~self.occ
        self.occ |= near
        self.static.add(j)
        self.log(t, "static", f"obstacle {j} stood {p.static_after_s:g} s at "
                              f"({at[0]:.1f}, {at[1]:.1f})")
        if not self.replan(t, at):
            self.static.discard(j)  # no way around: keep waiting for it to move

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
        for k in range(start, len(samples)):
            c = np.round(xy[k])
            if near[k] < p.safety_distance + 0.5 or self.occ[int(c[1]), int(c[0])]:
                continue
            i = min(int(np.searchsorted(cum, samples[k], side="right")), len(pts) - 1)
            if line_of_sight(self.occ, c, pts[i]):
                target, seg_end = c, i
                break
        if target is None:
            target, seg_end = np.array(self.sc.goal, dtype=float), len(pts)
        try:
            detour = navigate(self.occ, self.pos, target, turn_weight=p.turn_weight)
        except NoPathError as exc:
            self.log(t, "blocked", str(exc))
            return False
        rest = seg_end - 1  # index into wps of pts[seg_end]
        keep_w, keep_t = self.wps[rest:], self.tags[rest:]
        if seg_end >= len(pts) or (keep_w and np.allclose(keep_w[0], target)):
            keep_w, keep_t = keep_w[1:], keep_t[1:]
        last = "goal" if not keep_w else "recovery"
        self.wps = [d for d in detour] + keep_w
        self.tags = ["subgoal"] * (len(detour) - 1) + [last] + keep_t
        self.mode = "replan"
        self.log(t, "replan", f"detour of {len(detour)} sub-goal(s), rejoin the route at "
                              f"({target[0]:.0f}, {target[1]:.0f})")
        return True

    # motion --------------------------------------------------------------------------------
    def move(self, t: float, v_target: float) -> None:
        p = self.p
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
        while step > 0 and self.wps:
            d = self.wps[0] - self.pos
            dist = math.hypot(d[0], d[1])
            if dist <= step:
                self.pos = self.wps.pop(0)
                tag = self.tags.pop(0)
                step -= dist
                frac = 1.0 - step / (self.v * p.dt)
                if tag in ("subgoal", "sidestep", "recovery"):
                    detail = f"({self.pos[0]:.0f}, {self.pos[1]:.0f})"
                    self.log(t + frac * p.dt, tag if tag == "recovery" else "subgoal", detail)
            else:
                self.pos = self.pos + d * (step / dist)
                step = 0.0


def simulate(scenario: AgvScenario, *, free_time: float | None = None) -> AgvRun:
    """Run a scenario to success, collision or timeout.

    ``free_time`` is the obstacle-free arrival time if already known (it is
    otherwise measured by a second run without the moving obstacles).

    Raises:
        NoPathError: the goal cannot be reached on the static map.
    """
    p = scenario.params
    route = plan_route(scenario.world, scenario.start, scenario.goal, p)
    if free_time is None:
        free_time = (simulate(replace(scenario, obstacles=()), free_time=0.0).time_s
                     if scenario.obstacles else None)
    agv = _Agv(scenario, route)
    n_steps = int(math.ceil(p.max_time_s / p.dt))
    times = np.arange(n_steps + 1) * p.dt
    m = len(scenario.obstacles)
    obs_traj = (np.stack([ob.positions(times) for ob in scenario.obstacles])
                if m else np.zeros((0, n_steps + 1, 2)))
    traj = np.zeros((n_steps + 1, 2))
    speeds = np.zeros(n_steps + 1)
    min_sep = math.inf
    outcome = "timeout"
    k = 0
    for k in range(n_steps + 1):
        t = times[k]
        traj[k], speeds[k] = agv.pos, agv.v
        now = obs_traj[:, k]
        dist = np.hypot(now[:, 0] - agv.pos[0], now[:, 1] - agv.pos[1]) if m else np.zeros(0)
        if m:
            min_sep = min(min_sep, float(dist.min()))
            if dist.min() < p.collision_distance:
                outcome = "collision"
                agv.log(t, "collision", f"obstacle {int(dist.argmin())} at distance "
                                        f"{dist.min():.2f}")
                break
        if not agv.wps:
            outcome = "success"
            agv.log(t, "goal")
            break
        if k == n_steps:
            agv.log(t, "timeout")
            break
        v_target = p.v_nominal
        if p.collision_check and m:
            vel = (now - obs_traj[:, k - 1]) / p.dt if k else np.zeros_like(now)
            moving = np.hypot(vel[:, 0], vel[:, 1]) > 1e-9
            for j in list(agv.static):
                if moving[j]:
                    agv.static.discard(j)
            ids = np.flatnonzero((dist <= p.sensor_range)
                                 & ~np.isin(np.arange(m), list(agv.static)))
            agv.conflict = -1
            v_target = agv.decide(t, now[ids], vel[ids], ids)
            j = agv.conflict
            for i in range(m):
                if i == j and agv.v <= 1e-12 and agv.mode == "stop" and not moving[i]:
                    agv.stand_time[i] += p.dt
                else:
                    agv.stand_time[i] = 0.0
            if j >= 0 and agv.stand_time[j] >= p.static_after_s - 1e-9:
                agv.stand_time[j] = 0.0
                agv.make_static(t, j, now[j])
                v_target = 0.0
        agv.move(t, v_target)
    n = k + 1
    return AgvRun(
        scenario=scenario.name, outcome=outcome, time_s=float(times[k]),
        free_time_s=float(times[k]) if free_time is None else float(free_time),
        min_separation=min_sep, times=times[:n].copy(), trajectory=traj[:n].copy(),
        speeds=speeds[:n].copy(), obstacle_positions=obs_traj[:, :n].copy(),
        events=tuple(agv.events), planned_route=route, static_cells=agv.static_cells,
        world=scenario.world, params=p)
