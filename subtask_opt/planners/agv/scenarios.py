"""Scenarios of the AGV simulation: the paper's experiments and a random suite.

The paper's maps are figures that did not survive, so each experiment is
rebuilt on a 400 x 400-pixel image (40 x 40 cells of 10 x 10 pixels) that
shows the behaviour it describes:

* ``"1"`` - static obstacles only; the AGV moves from corner to corner.
* ``"2-1"`` - moving obstacles (1 u/s, like the AGV) approach from the AGV's
  left and right: it yields (brakes) to the one that reaches the crossing
  first and keeps its normal speed ahead of the one it reaches first (rule
  5-2-1).
* ``"2-2"`` - the route bends; an obstacle crosses it from left to right
  while the AGV approaches (a moving crossing in the event log) and stops on
  it: the AGV waits, takes it as static after ~10 s, re-plans around it and
  recovers its route.
* ``"2-3"`` - the route bends; an obstacle from the right reaches the crossing
  with the AGV: the AGV passes behind it and recovers its route.

:func:`random_agv_scenario` builds a seeded map with 1-5 obstacles crossing
the AGV's route, and :func:`run_agv_suite` runs many of them (with odometry
drift, with and without check points). A scenario can also be a JSON file
(:func:`load_scenario`), read defensively: size, nesting depth, NaN and types
are checked before anything is built.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError, SubtaskOptError, require_int
from subtask_opt.base.files import parse_json, read_text
from subtask_opt.base.progress import progress_bar
from subtask_opt.base.results import Outcome
from subtask_opt.planners.agv import _kernels as K
from subtask_opt.planners.agv.certainty_grid import CertaintyParams, certainty_grid
from subtask_opt.planners.agv.navigation import build_tree
from subtask_opt.planners.agv.quadtree import Quadtree
from subtask_opt.planners.agv.simulation import (
    AgvParams,
    AgvRun,
    AgvScenario,
    MovingObstacle,
    plan_route,
    simulate,
)
from subtask_opt.planners.grid.world import GridWorld

IMAGE_PX = 400


def draw_image(rects: list[tuple[int, int, int, int]], discs: tuple = (),
               size: int = IMAGE_PX) -> np.ndarray:
    """A white grey-level image with black rectangles ``(x0, y0, x1, y1)`` and
    discs ``(cx, cy, r)``, all in pixels."""
    img = np.ones((size, size))
    for x0, y0, x1, y1 in rects:
        img[y0:y1, x0:x1] = 0.0
    yy, xx = np.mgrid[0:size, 0:size]
    for cx, cy, r in discs:
        img[(xx - cx) ** 2 + (yy - cy) ** 2 <= r * r] = 0.0
    return img


def _world(img: np.ndarray, name: str) -> tuple[GridWorld, np.ndarray]:
    """The global map (rule 1-1) and the 2-bit local map of an image."""
    cg = certainty_grid(img, CertaintyParams())
    return cg.world(name), cg.local_states()


def _cells(*rects: tuple[int, int, int, int]) -> list[tuple[int, int, int, int]]:
    """Rectangles given in cells (x0, y0, x1, y1), as pixels."""
    return [(10 * a, 10 * b, 10 * c, 10 * d) for a, b, c, d in rects]


def scenario_1() -> AgvScenario:
    """Experiment 1: static obstacles only (a disc leaves mixed cells)."""
    img = draw_image(_cells((8, 5, 14, 20), (20, 11, 31, 17), (15, 25, 22, 34), (30, 23, 35, 36)),
                     discs=((255, 75, 28),))
    world, states = _world(img, "experiment 1")
    return AgvScenario("1", world, (2, 37), (37, 2), states=states,
                       description="static obstacles: corner to corner")


def scenario_2_1() -> AgvScenario:
    """Experiment 2-1: obstacles at 1 u/s from the AGV's left and right."""
    img = draw_image(_cells((5, 3, 20, 8), (22, 32, 36, 37)))
    world, states = _world(img, "experiment 2-1")
    obstacles = (
        MovingObstacle([(12, 11), (12, 36)], speed=1.0, name="from the left"),
        MovingObstacle([(27, 31), (27, 10)], speed=1.0, start_time=START_2_1,
                       name="from the right"),
    )
    return AgvScenario("2-1", world, (2, 20), (37, 20), obstacles, states=states,
                       description="obstacles approach from the left and the right: "
                                   "yield to the first, keep speed ahead of the second")


def scenario_2_2() -> AgvScenario:
    """Experiment 2-2: the route bends; an obstacle crosses it from left to
    right and stops on it."""
    img = draw_image(_cells((14, 16, 26, 40), (30, 0, 40, 8)))
    world, states = _world(img, "experiment 2-2")
    obstacles = (MovingObstacle(PATH_2_2, speed=1.0, start_time=START_2_2,
                                name="crosses left to right, stops on the route"),)
    return AgvScenario("2-2", world, (3, 36), (36, 12), obstacles, states=states,
                       description="an obstacle crossing left to right stops on the route: "
                                   "wait, take it as static, re-plan, recover")


def scenario_2_3() -> AgvScenario:
    """Experiment 2-3: the route bends; an obstacle from the right reaches the
    crossing with the AGV."""
    img = draw_image(_cells((14, 16, 26, 40), (30, 0, 40, 8)))
    world, states = _world(img, "experiment 2-3")
    obstacles = (MovingObstacle([(28, 30), (28, 2)], start_time=21.5,
                                name="from the right"),)
    return AgvScenario("2-3", world, (3, 36), (36, 12), obstacles, states=states,
                       description="an obstacle from the right reaches the crossing with "
                                   "the AGV: pass behind it, recover the route")


START_2_1 = 17.0
PATH_2_2 = [(24.0, 3.0), (24.0, 14.5)]
START_2_2 = 22.0

PAPER_SCENARIOS: dict[str, Callable[[], AgvScenario]] = {
    "1": scenario_1, "2-1": scenario_2_1, "2-2": scenario_2_2, "2-3": scenario_2_3,
}


def suite_params() -> AgvParams:
    """Parameters of the random suite: the defaults with odometry drift on."""
    return AgvParams(drift=True)


def random_agv_scenario(seed: int, *, n_obstacles: int | None = None,
                        params: AgvParams | None = None) -> AgvScenario:
    """A seeded random map (static blocks) with ``n_obstacles`` (default: 1-5
    at random) obstacles at 1 u/s crossing the AGV's planned route.

    Each obstacle crosses the route at 60-120 degrees, reaching the crossing
    within +-3 s of the AGV's obstacle-free arrival there, and starts and ends
    at least 2.5 cells away from the route.
    """
    require_int("random_agv_scenario", "seed", seed, 0, 2**63 - 1)
    if n_obstacles is not None:
        require_int("random_agv_scenario", "n_obstacles", n_obstacles, 0, 50)
    params = suite_params() if params is None else params
    if not isinstance(params, AgvParams):
        raise ParameterError(f"random_agv_scenario.params must be AgvParams, got {params!r:.80}")
    rng = np.random.default_rng(seed)
    n_obs = int(rng.integers(1, 6)) if n_obstacles is None else n_obstacles
    for _ in range(50):
        rects = []
        for _ in range(int(rng.integers(2, 6))):
            w, h = rng.integers(3, 10, size=2)
            x0, y0 = rng.integers(6, 34 - w), rng.integers(6, 34 - h)
            rects.append((int(x0), int(y0), int(x0 + w), int(y0 + h)))
        world, states = _world(draw_image(_cells(*rects)), f"random {seed}")
        start = (int(rng.integers(1, 5)), int(rng.integers(35, 39)))
        goal = (int(rng.integers(35, 39)), int(rng.integers(1, 5)))
        try:
            route = plan_route(world, start, goal, params, states=states)
        except SubtaskOptError:
            continue
        break
    else:  # pragma: no cover - 50 failures in a row
        raise InputDataError(f"random_agv_scenario({seed}): no connected map found")
    tree = build_tree(np.asarray(world.occupancy, dtype=bool))
    cum = np.zeros(len(route))
    cum[1:] = np.cumsum(np.hypot(*np.diff(route, axis=0).T))
    obstacles = []
    for i in range(n_obs):
        for _ in range(30):
            ob = _crossing_obstacle(rng, route, cum, tree, start, goal, params, i)
            if ob is not None:
                obstacles.append(ob)
                break
    return AgvScenario(f"random-{seed}", world, start, goal, tuple(obstacles), params,
                       description=f"random map, {len(obstacles)} crossing obstacle(s)",
                       states=states)


def _crossing_obstacle(rng: np.random.Generator, route: np.ndarray, cum: np.ndarray,
                       tree: Quadtree, start: tuple[int, int], goal: tuple[int, int],
                       params: AgvParams, i: int) -> MovingObstacle | None:
    s = rng.uniform(0.15, 0.85) * cum[-1]
    seg = min(int(np.searchsorted(cum, s, side="right")), len(route) - 1)
    a, b = route[seg - 1], route[seg]
    tangent = (b - a) / max(np.hypot(*(b - a)), 1e-12)
    x = np.array(K.point_on_polyline(route, cum, s))
    ang = math.radians(rng.uniform(60, 120)) * rng.choice([-1.0, 1.0])
    c, sn = math.cos(ang), math.sin(ang)
    u = np.array([c * tangent[0] - sn * tangent[1], sn * tangent[0] + c * tangent[1]])
    arrive = s / params.v_nominal + rng.uniform(-3.0, 3.0)
    before = rng.uniform(4.0, 10.0)
    start_time = arrive - before
    if start_time < 0:
        before, start_time = arrive, 0.0
    p0, p1 = x - u * before, x + u * rng.uniform(4.0, 8.0)
    h, w = tree.shape
    for q in (p0, p1):
        if not (0 <= q[0] <= w - 1 and 0 <= q[1] <= h - 1):
            return None
        if _dist_to_polyline(q, route) < 2.5:
            return None
        if min(np.hypot(*(q - np.array(start))), np.hypot(*(q - np.array(goal)))) < 3.0:
            return None
    if not tree.segment_free(p0, p1):
        return None
    return MovingObstacle([p0, p1], 1.0, float(start_time), f"obstacle {i}")


def _dist_to_polyline(q: np.ndarray, pts: np.ndarray) -> float:
    best = math.inf
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        d = b - a
        L2 = float(d @ d)
        f = 0.0 if L2 == 0 else min(1.0, max(0.0, float((q - a) @ d) / L2))
        best = min(best, math.hypot(*(a + f * d - q)))
    return best


# -- scenario files -------------------------------------------------------------------------
MAX_SCENARIO_BYTES = 1 << 20
"""A scenario file may be at most this large (1 MiB)."""
MAX_JSON_DEPTH = 8
"""Arrays and objects may nest at most this deep (a scenario needs 4)."""
_TOP_KEYS = {"name", "description", "image", "cell_px", "density_factor", "map", "start", "goal",
             "obstacles", "params"}
_OBSTACLE_KEYS = {"path", "speed", "start_time", "name"}


def _read_json(path: Path) -> Any:
    return parse_json(read_text(path, "scenario", max_bytes=MAX_SCENARIO_BYTES),
                      f"scenario {str(path)!r}", max_depth=MAX_JSON_DEPTH)


def load_scenario(path: str | Path) -> AgvScenario:
    """A scenario from a JSON file.

    Keys: ``name``; the map as ``image`` (a file, relative to the JSON file,
    read as a certainty grid with ``cell_px`` and ``density_factor``) or
    ``map`` (list of ASCII rows, ``.`` free, ``@``/``#`` blocked); ``start``
    and ``goal`` cells ``[x, y]``; ``obstacles``: list of ``{"path": [[x, y],
    ...], "speed": 1.0, "start_time": 0.0, "name": ""}``; ``params``:
    :class:`AgvParams` fields.

    Raises:
        InputDataError: unreadable, over :data:`MAX_SCENARIO_BYTES`, nested
            deeper than :data:`MAX_JSON_DEPTH`, not JSON, NaN/Infinity, a
            wrong type or an unknown key.
        ParameterError: a parameter out of range (including a run that
            would record over 1 GiB).
        UnreachableError: start or goal off the map or not a free cell.
    """
    path = Path(path)
    data = _read_json(path)
    where = f"scenario {str(path)!r}"
    if not isinstance(data, dict):
        raise InputDataError(f"{where} must be a JSON object, got {type(data).__name__}")
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise InputDataError(f"{where}: unknown key(s) {unknown}; allowed: {sorted(_TOP_KEYS)}")
    for key in ("start", "goal"):
        if key not in data:
            raise InputDataError(f"{where} has no {key!r}")
    for key in ("name", "description", "image"):
        if key in data and not isinstance(data[key], str):
            raise InputDataError(f"{where}: {key!r} must be a string, got {data[key]!r:.80}")
    name = data.get("name", path.stem)
    states = None
    if "image" in data and "map" in data:
        raise InputDataError(f"{where} has both an 'image' and a 'map'; give one")
    if "image" in data:
        cp = CertaintyParams(data.get("cell_px", 10), data.get("density_factor", 30))
        cg = certainty_grid(path.parent / data["image"], cp)
        world, states = cg.world(name), cg.local_states()
    elif "map" in data:
        rows = data["map"]
        if not isinstance(rows, list) or not rows or not all(isinstance(r, str) for r in rows):
            raise InputDataError(f"{where}: 'map' must be a non-empty list of strings")
        world = GridWorld.from_ascii("\n".join(rows), name=name)
    else:
        raise InputDataError(f"{where} needs an 'image' or a 'map'")
    raw_obstacles = data.get("obstacles", [])
    if not isinstance(raw_obstacles, list):
        raise InputDataError(f"{where}: 'obstacles' must be a list, got "
                             f"{type(raw_obstacles).__name__}")
    obstacles = []
    for i, ob in enumerate(raw_obstacles):
        if not isinstance(ob, dict) or "path" not in ob:
            raise InputDataError(f"{where}: obstacles[{i}] must be an object with a 'path'")
        bad = sorted(set(ob) - _OBSTACLE_KEYS)
        if bad:
            raise InputDataError(f"{where}: obstacles[{i}] has unknown key(s) {bad}; "
                                 f"allowed: {sorted(_OBSTACLE_KEYS)}")
        obstacles.append(MovingObstacle(ob["path"], ob.get("speed", 1.0),
                                        ob.get("start_time", 0.0), ob.get("name", "")))
    params = AgvParams.from_dict(data.get("params", {}))
    return AgvScenario(name, world, data["start"], data["goal"], tuple(obstacles), params,
                       data.get("description", ""), states)


def get_scenario(name: str, seed: int = 0) -> AgvScenario:
    """A paper scenario by name (``1``, ``2-1``, ``2-2``, ``2-3``), ``random``
    (built from ``seed``), or a path to a JSON scenario file."""
    if name in PAPER_SCENARIOS:
        return PAPER_SCENARIOS[name]()
    if name == "random":
        return random_agv_scenario(seed)
    if name.endswith(".json") or Path(name).exists():
        return load_scenario(name)
    raise ParameterError(
        f"unknown scenario {name!r}: use one of {', '.join(PAPER_SCENARIOS)}, 'random', "
        f"or a path to a .json file")


@dataclass(frozen=True)
class SuiteReport:
    """Totals of a random suite.

    The suite runs every scenario with check points (the main numbers) and,
    when drift is on, again without them (``*_no_check``), same drift seed.
    """

    runs: int
    success: int
    collisions: int
    timeouts: int
    no_path: int
    mean_delay_s: float
    min_separation: float
    mean_drift_error: float
    max_drift_error: float
    success_no_check: int
    collisions_no_check: int
    mean_drift_error_no_check: float
    max_drift_error_no_check: float
    seconds: float
    seed: int
    collision_check: bool
    drift: bool
    outcomes: tuple[str, ...]
    delays: tuple[float, ...] = ()
    drift_errors: tuple[float, ...] = ()
    drift_errors_no_check: tuple[float, ...] = ()

    @property
    def success_rate(self) -> float:
        return self.success / self.runs if self.runs else 0.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe totals (nan/inf as None) and per-run lists."""
        def num(v: float) -> float | None:
            return v if math.isfinite(v) else None

        return {"runs": self.runs, "success": self.success, "collisions": self.collisions,
                "timeouts": self.timeouts, "no_path": self.no_path,
                "success_rate": self.success_rate,
                "mean_delay_s": num(self.mean_delay_s),
                "min_separation": num(self.min_separation),
                "mean_drift_error": num(self.mean_drift_error),
                "max_drift_error": num(self.max_drift_error),
                "success_no_check": self.success_no_check,
                "collisions_no_check": self.collisions_no_check,
                "mean_drift_error_no_check": num(self.mean_drift_error_no_check),
                "max_drift_error_no_check": num(self.max_drift_error_no_check),
                "seconds": self.seconds, "seed": self.seed,
                "collision_check": self.collision_check, "drift": self.drift,
                "outcomes": list(self.outcomes),
                "delays": [num(d) for d in self.delays],
                "drift_errors": list(self.drift_errors),
                "drift_errors_no_check": list(self.drift_errors_no_check)}

    def summary(self) -> str:
        check = "on" if self.collision_check else "OFF"
        text = (f"{self.runs} runs (seed {self.seed}, collision check {check}): "
                f"{self.success} success ({100 * self.success_rate:.1f}%), "
                f"{self.collisions} collisions, {self.timeouts} timeouts, "
                f"mean delay {self.mean_delay_s:.2f} s, "
                f"min separation {self.min_separation:.2f} cells")
        if self.drift:
            text += (f"; drift error mean/max {self.mean_drift_error:.3f}/"
                     f"{self.max_drift_error:.2f} cells with check points, "
                     f"{self.mean_drift_error_no_check:.3f}/{self.max_drift_error_no_check:.2f}"
                     f" without ({self.success_no_check} success, "
                     f"{self.collisions_no_check} collisions)")
        return text + f"; {self.seconds:.1f} s"


def agv_suite_run(seed: int, params: AgvParams) -> tuple[AgvRun, AgvRun | None]:
    """One run of the suite: the random scenario of ``seed`` with check points and,
    when drift is on, again without them (same drift seed); picklable for workers."""
    sc = random_agv_scenario(seed, params=params)
    run = simulate(sc, seed=seed)
    bare = (simulate(sc.with_params(check_points=False), seed=seed, free_time=run.free_time_s)
            if params.drift else None)
    return run, bare


def run_agv_suite(n: int, seed: int, *, params: AgvParams | None = None,
                  progress: bool = False,
                  map_runs: Callable[[Callable[[int], Any], list[int]], list[Any]] | None = None
                  ) -> SuiteReport:
    """Run ``n`` random scenarios with seeds ``seed, seed + 1, ...`` (scenario
    and drift seed alike); default params: :func:`suite_params` (drift on).

    ``map_runs(fn, seeds)`` (default: a loop here, with a progress bar when
    ``progress``) returns ``[fn(s) for s in seeds]`` in order; pass one that runs
    them in parallel (:func:`subtask_opt.batch.suite_mapper`). Every run depends
    on its seed only, so the report is the same wherever the runs ran.
    """
    require_int("run_agv_suite", "n", n, 1, 100_000)
    require_int("run_agv_suite", "seed", seed, 0, 2**63 - 1 - n)
    params = suite_params() if params is None else params
    t0 = time.perf_counter()
    one = partial(agv_suite_run, params=params)
    if map_runs is None:
        pairs = []
        with progress_bar(progress, total=n, desc="agv suite", unit="run") as bar:
            for i in range(n):
                pairs.append(one(seed + i))
                bar.update()
    else:
        pairs = map_runs(one, list(range(seed, seed + n)))
    runs: list[AgvRun] = [run for run, _ in pairs]
    bare: list[AgvRun] = [b for _, b in pairs if b is not None]
    ok = [r for r in runs if r.success]
    seps = [r.min_separation for r in runs if math.isfinite(r.min_separation)]
    errs = [r.mean_drift_error for r in runs]
    errs_bare = [r.mean_drift_error for r in bare]
    return SuiteReport(
        runs=n, success=len(ok), collisions=sum(r.outcome == Outcome.COLLISION for r in runs),
        timeouts=sum(r.outcome == Outcome.TIMEOUT for r in runs),
        no_path=sum(r.outcome == Outcome.NO_PATH for r in runs),
        mean_delay_s=float(np.mean([r.delay_s for r in ok])) if ok else math.nan,
        min_separation=min(seps) if seps else math.inf,
        mean_drift_error=float(np.mean(errs)),
        max_drift_error=max(r.max_drift_error for r in runs),
        success_no_check=sum(r.success for r in bare),
        collisions_no_check=sum(r.outcome == Outcome.COLLISION for r in bare),
        mean_drift_error_no_check=float(np.mean(errs_bare)) if bare else math.nan,
        max_drift_error_no_check=max((r.max_drift_error for r in bare), default=math.nan),
        seconds=time.perf_counter() - t0, seed=seed,
        collision_check=params.collision_check, drift=params.drift,
        outcomes=tuple(r.outcome.value for r in runs),
        delays=tuple(r.delay_s for r in runs), drift_errors=tuple(errs),
        drift_errors_no_check=tuple(errs_bare))


__all__ = ["MAX_JSON_DEPTH", "MAX_SCENARIO_BYTES", "PAPER_SCENARIOS", "SuiteReport",
           "agv_suite_run", "draw_image", "get_scenario", "load_scenario", "random_agv_scenario",
           "run_agv_suite", "scenario_1", "scenario_2_1", "scenario_2_2", "scenario_2_3",
           "suite_params"]
