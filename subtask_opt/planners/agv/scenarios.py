"""Scenarios of the AGV simulation: the paper's experiments and a random suite.

The paper's maps are figures that did not survive, so each experiment is
rebuilt on a 400 x 400-pixel image (40 x 40 cells of 10 x 10 pixels) that
shows the behaviour it describes:

* ``"1"`` - static obstacles only; the AGV moves from corner to corner.
* ``"2-1"`` - moving obstacles approach from the AGV's left and right: it
  yields (brakes) to the one that reaches the crossing first and speeds up to
  pass ahead of the one it reaches first.
* ``"2-2"`` - the route bends; an obstacle crossing from left to right stops on
  it: the AGV waits, takes it as static after ~10 s, re-plans around it and
  recovers its route.
* ``"2-3"`` - the route bends; an obstacle from the right reaches the crossing
  with the AGV: the AGV passes behind it and recovers its route.

:func:`random_scenario` builds a seeded map with 1-5 obstacles crossing the
AGV's route, and :func:`run_suite` runs many of them. A scenario can also be a
JSON file (:func:`load_scenario`).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError, SubtaskOptError, require_int
from subtask_opt.base.progress import progress_bar
from subtask_opt.planners.agv import _kernels as K
from subtask_opt.planners.agv.certainty_grid import CertaintyParams, certainty_grid
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


def _world(img: np.ndarray, name: str) -> GridWorld:
    return certainty_grid(img, CertaintyParams()).world(name)


def _cells(*rects: tuple[int, int, int, int]) -> list[tuple[int, int, int, int]]:
    """Rectangles given in cells (x0, y0, x1, y1), as pixels."""
    return [(10 * a, 10 * b, 10 * c, 10 * d) for a, b, c, d in rects]


def scenario_1() -> AgvScenario:
    img = draw_image(_cells((8, 5, 14, 20), (20, 11, 31, 17), (15, 25, 22, 34), (30, 23, 35, 36)),
                     discs=((255, 75, 28),))
    return AgvScenario("1", _world(img, "experiment 1"), (2, 37), (37, 2),
                       description="static obstacles: corner to corner")


def scenario_2_1() -> AgvScenario:
    img = draw_image(_cells((5, 3, 20, 8), (22, 32, 36, 37)))
    obstacles = (
        MovingObstacle([(12, 15.5), (12, 36)], speed=0.5, name="from the left"),
        MovingObstacle([(26, 31), (26, 10)], start_time=17.0, name="from the right"),
    )
    return AgvScenario("2-1", _world(img, "experiment 2-1"), (2, 20), (37, 20), obstacles,
                       description="obstacles approach from the left and the right: "
                                   "yield to the first, pass ahead of the second")


def scenario_2_2() -> AgvScenario:
    img = draw_image(_cells((14, 16, 26, 40), (30, 0, 40, 8)))
    obstacles = (MovingObstacle([(24, 3), (24, 13.5)], start_time=10.0, name="stops on the route"),)
    return AgvScenario("2-2", _world(img, "experiment 2-2"), (3, 36), (36, 12), obstacles,
                       description="an obstacle crossing left to right stops on the route: "
                                   "wait, take it as static, re-plan, recover")


def scenario_2_3() -> AgvScenario:
    img = draw_image(_cells((14, 16, 26, 40), (30, 0, 40, 8)))
    obstacles = (MovingObstacle([(28, 30), (28, 2)], start_time=21.5,
                                name="from the right"),)
    return AgvScenario("2-3", _world(img, "experiment 2-3"), (3, 36), (36, 12), obstacles,
                       description="an obstacle from the right reaches the crossing with "
                                   "the AGV: pass behind it, recover the route")


PAPER_SCENARIOS: dict[str, Callable[[], AgvScenario]] = {
    "1": scenario_1, "2-1": scenario_2_1, "2-2": scenario_2_2, "2-3": scenario_2_3,
}


def random_scenario(seed: int, *, n_obstacles: int | None = None,
                    params: AgvParams | None = None) -> AgvScenario:
    """A seeded random map (static blocks) with ``n_obstacles`` (default: 1-5
    at random) obstacles at 1 cell/s crossing the AGV's planned route.

    Each obstacle crosses the route at 60-120 degrees, reaching the crossing
    within +-3 s of the AGV's obstacle-free arrival there, and starts and ends
    at least 2.5 cells away from the route.
    """
    require_int("random_scenario", "seed", seed, 0)
    if n_obstacles is not None:
        require_int("random_scenario", "n_obstacles", n_obstacles, 0)
    params = AgvParams() if params is None else params
    rng = np.random.default_rng(seed)
    n_obs = int(rng.integers(1, 6)) if n_obstacles is None else n_obstacles
    for _ in range(50):
        rects = []
        for _ in range(int(rng.integers(2, 6))):
            w, h = rng.integers(3, 10, size=2)
            x0, y0 = rng.integers(6, 34 - w), rng.integers(6, 34 - h)
            rects.append((int(x0), int(y0), int(x0 + w), int(y0 + h)))
        world = _world(draw_image(_cells(*rects)), f"random {seed}")
        start = (int(rng.integers(1, 5)), int(rng.integers(35, 39)))
        goal = (int(rng.integers(35, 39)), int(rng.integers(1, 5)))
        try:
            route = plan_route(world, start, goal, params)
        except SubtaskOptError:
            continue
        break
    else:  # pragma: no cover - 50 failures in a row
        raise InputDataError(f"random_scenario({seed}): no connected map found")
    occ = np.array(world.occupancy)
    cum = np.zeros(len(route))
    cum[1:] = np.cumsum(np.hypot(*np.diff(route, axis=0).T))
    obstacles = []
    for i in range(n_obs):
        for _ in range(30):
            ob = _crossing_obstacle(rng, route, cum, occ, start, goal, params, i)
            if ob is not None:
                obstacles.append(ob)
                break
    return AgvScenario(f"random-{seed}", world, start, goal, tuple(obstacles), params,
                       description=f"random map, {len(obstacles)} crossing obstacle(s)")


def _crossing_obstacle(rng, route, cum, occ, start, goal, params, i) -> MovingObstacle | None:
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
    h, w = occ.shape
    for q in (p0, p1):
        if not (0 <= q[0] <= w - 1 and 0 <= q[1] <= h - 1):
            return None
        if _dist_to_polyline(q, route) < 2.5:
            return None
        if min(np.hypot(*(q - np.array(start))), np.hypot(*(q - np.array(goal)))) < 3.0:
            return None
    if not K.segment_free(occ, p0[0], p0[1], p1[0], p1[1]):
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


def load_scenario(path: str | Path) -> AgvScenario:
    """A scenario from a JSON file.

    Keys: ``name``; the map as ``image`` (a file, relative to the JSON file,
    read as a certainty grid with ``cell_px`` and ``density_factor``) or
    ``map`` (list of ASCII rows, ``.`` free, ``@``/``#`` blocked); ``start``
    and ``goal`` cells ``[x, y]``; ``obstacles``: list of ``{"path": [[x, y],
    ...], "speed": 1.0, "start_time": 0.0}``; ``params``: AgvParams fields.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError) as exc:
        raise InputDataError(f"cannot read scenario {str(path)!r}: {exc}") from None
    except json.JSONDecodeError as exc:
        raise InputDataError(f"scenario {str(path)!r} is not valid JSON: {exc}") from None
    if not isinstance(data, dict):
        raise InputDataError(f"scenario {str(path)!r} must be a JSON object")
    for key in ("start", "goal"):
        if key not in data:
            raise InputDataError(f"scenario {str(path)!r} has no {key!r}")
    name = str(data.get("name", path.stem))
    if "image" in data:
        cp = CertaintyParams(data.get("cell_px", 10), data.get("density_factor", 30))
        world = certainty_grid(path.parent / str(data["image"]), cp).world(name)
    elif "map" in data:
        rows = data["map"]
        if not isinstance(rows, list) or not all(isinstance(r, str) for r in rows):
            raise InputDataError(f"scenario {str(path)!r}: 'map' must be a list of strings")
        world = GridWorld.from_ascii("\n".join(rows), name=name)
    else:
        raise InputDataError(f"scenario {str(path)!r} needs an 'image' or a 'map'")
    obstacles = []
    for i, ob in enumerate(data.get("obstacles", [])):
        if not isinstance(ob, dict) or "path" not in ob:
            raise InputDataError(f"scenario {str(path)!r}: obstacles[{i}] needs a 'path'")
        obstacles.append(MovingObstacle(ob["path"], ob.get("speed", 1.0),
                                        ob.get("start_time", 0.0), ob.get("name", "")))
    params = AgvParams.from_dict(data.get("params", {}))
    return AgvScenario(name, world, data["start"], data["goal"], tuple(obstacles), params,
                       str(data.get("description", "")))


def get_scenario(name: str, seed: int = 0) -> AgvScenario:
    """A paper scenario by name (``1``, ``2-1``, ``2-2``, ``2-3``), ``random``
    (built from ``seed``), or a path to a JSON scenario file."""
    if name in PAPER_SCENARIOS:
        return PAPER_SCENARIOS[name]()
    if name == "random":
        return random_scenario(seed)
    if name.endswith(".json") or Path(name).exists():
        return load_scenario(name)
    raise ParameterError(
        f"unknown scenario {name!r}: use one of {', '.join(PAPER_SCENARIOS)}, 'random', "
        f"or a path to a .json file")


@dataclass(frozen=True)
class SuiteReport:
    """Totals of a random suite."""

    runs: int
    success: int
    collisions: int
    timeouts: int
    mean_delay_s: float
    min_separation: float
    seconds: float
    seed: int
    collision_check: bool
    outcomes: tuple[str, ...]

    @property
    def success_rate(self) -> float:
        return self.success / self.runs if self.runs else 0.0

    def to_dict(self) -> dict[str, Any]:
        return {"runs": self.runs, "success": self.success, "collisions": self.collisions,
                "timeouts": self.timeouts, "success_rate": self.success_rate,
                "mean_delay_s": self.mean_delay_s, "min_separation": self.min_separation,
                "seconds": self.seconds, "seed": self.seed,
                "collision_check": self.collision_check, "outcomes": list(self.outcomes)}

    def summary(self) -> str:
        check = "on" if self.collision_check else "OFF"
        return (f"{self.runs} runs (seed {self.seed}, collision check {check}): "
                f"{self.success} success ({100 * self.success_rate:.1f}%), "
                f"{self.collisions} collisions, {self.timeouts} timeouts, "
                f"mean delay {self.mean_delay_s:.2f} s, "
                f"min separation {self.min_separation:.2f} cells, {self.seconds:.1f} s")


def run_suite(n: int, seed: int, *, params: AgvParams | None = None,
              progress: bool = False) -> SuiteReport:
    """Run ``n`` random scenarios with seeds ``seed, seed + 1, ...``."""
    require_int("run_suite", "n", n, 1)
    require_int("run_suite", "seed", seed, 0)
    params = AgvParams() if params is None else params
    t0 = time.perf_counter()
    runs: list[AgvRun] = []
    with progress_bar(progress, total=n, desc="agv suite", unit="run") as bar:
        for i in range(n):
            sc = random_scenario(seed + i, params=params)
            runs.append(simulate(sc))
            bar.update()
    ok = [r for r in runs if r.success]
    seps = [r.min_separation for r in runs if math.isfinite(r.min_separation)]
    return SuiteReport(
        runs=n, success=len(ok), collisions=sum(r.outcome == "collision" for r in runs),
        timeouts=sum(r.outcome == "timeout" for r in runs),
        mean_delay_s=float(np.mean([r.delay_s for r in ok])) if ok else math.nan,
        min_separation=min(seps) if seps else math.inf,
        seconds=time.perf_counter() - t0, seed=seed,
        collision_check=params.collision_check,
        outcomes=tuple(r.outcome for r in runs))


__all__ = ["PAPER_SCENARIOS", "SuiteReport", "draw_image", "get_scenario", "load_scenario",
           "random_scenario", "run_suite", "scenario_1", "scenario_2_1", "scenario_2_2",
           "scenario_2_3"]
