"""Scenarios for the reactive navigators: the paper's three and a seeded random suite.

A :class:`Scenario` is a polygon world with a start pose and a goal point, in
metres (the robot defaults of :class:`.unicycle.Unicycle` are sized for them):

* ``simple`` - a few obstacles between start and goal (the paper's Fig. 7);
* ``u-trap`` - a U-shaped obstacle open toward the robot, on the straight line
  to the goal (Fig. 8: a pure reactive navigator is trapped inside);
* ``corridor`` - a corridor whose straight line to the goal is blocked by a
  wall followed by a row of boxes (Fig. 9).

:func:`random_navigation_scenario` builds cluttered worlds whose free space provably
connects start and goal for the robot's body: every obstacle is a convex
polygon inscribed in a disc, the discs are pairwise farther apart than
``gap`` and at least ``gap`` from the boundary, so the obstacles grown by
``gap / 2`` stay disjoint convex sets off the walls, and the complement of
such sets in a rectangle is connected.

Files: a scenario is stored as JSON ``{"world": {...}, "start": [x, y,
heading], "goal": [x, y], "name"?: str}`` (the world in
:class:`~subtask_opt.planners.polygon.world.PolygonWorld`'s JSON form, the
heading in radians); :meth:`Scenario.from_dict` and :meth:`Scenario.from_json`
read it and raise :class:`~subtask_opt.base.errors.InputDataError` for
anything malformed. :func:`resolve_world` accepts a scenario name, a built-in
world, a world file or a scenario file.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    SubtaskOptError,
    UnreachableError,
    require_int,
    require_positive,
)
from subtask_opt.base.files import parse_json, read_text
from subtask_opt.planners.polygon.world import MAX_FILE_BYTES, MAX_JSON_DEPTH, PolygonWorld

MAX_SUITE = 1_000_000
"""Most scenarios a random suite may hold."""

PAPER_SCENARIOS = ("simple", "u-trap", "corridor")


@dataclass(frozen=True)
class Scenario:
    """A world, a start pose ``(x, y, heading)`` and a goal ``(x, y)``."""

    name: str
    world: PolygonWorld
    start: tuple[float, float, float]
    goal: tuple[float, float]

    def __post_init__(self) -> None:
        if not isinstance(self.world, PolygonWorld):
            raise InputDataError(f"Scenario.world must be a PolygonWorld, got "
                                 f"{type(self.world).__name__}")
        object.__setattr__(self, "name", str(self.name))
        start = _numbers("Scenario.start", self.start, 3)
        goal = _numbers("Scenario.goal", self.goal, 2)
        self.world.check_point("start", start[:2])
        self.world.check_point("goal", goal)
        object.__setattr__(self, "start", (start[0], start[1], start[2]))
        object.__setattr__(self, "goal", (goal[0], goal[1]))

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "world": self.world.to_dict(),
                "start": list(self.start), "goal": list(self.goal)}

    @classmethod
    def from_dict(cls, d: Any) -> Scenario:
        """Build from the JSON form (see the module docstring).

        Raises:
            InputDataError: not an object, a missing key, or a malformed world,
                start or goal (start and goal must lie in the world's free space).
        """
        if not isinstance(d, dict):
            raise InputDataError(f"a scenario must be a JSON object, got {type(d).__name__}")
        missing = [k for k in ("world", "start", "goal") if k not in d]
        if missing:
            raise InputDataError(f"scenario is missing {', '.join(map(repr, missing))} "
                                 f"(keys present: {sorted(map(str, d))})")
        name = d.get("name", "")
        if not isinstance(name, str):
            raise InputDataError(f"scenario 'name' must be a string, got {name!r}")
        world = world_from_dict(d["world"])
        try:
            return cls(name or world.name, world, d["start"], d["goal"])
        except UnreachableError as exc:
            raise InputDataError(f"scenario: {exc}") from None

    @classmethod
    def from_json(cls, path: str | Path) -> Scenario:
        """Read a scenario file (InputDataError if missing, unreadable, too large or malformed)."""
        path = Path(path)
        d = _read_json(path)
        try:
            sc = cls.from_dict(d)
        except InputDataError as exc:
            raise InputDataError(f"{path}: {exc}") from None
        if not sc.name:
            object.__setattr__(sc, "name", path.stem)
        return sc

    def to_json(self, path: str | Path) -> None:
        """Write the scenario as JSON."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")


def world_from_dict(d: Any) -> PolygonWorld:
    """:meth:`PolygonWorld.from_dict`, with any other error of its parser turned into
    :class:`InputDataError` (so that arbitrary JSON never escapes as a TypeError)."""
    try:
        return PolygonWorld.from_dict(d)
    except SubtaskOptError:
        raise
    except (TypeError, ValueError, OverflowError, RecursionError) as exc:
        raise InputDataError(f"malformed polygon world: {exc}") from None


def _numbers(label: str, value: Any, n: int) -> tuple[float, ...]:
    """``n`` finite floats from a list/tuple/array of real numbers, or InputDataError."""
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__"):
        raise InputDataError(f"{label} must be {n} numbers, got {value!r}")
    items = list(value)
    if len(items) != n or any(isinstance(v, bool) or not isinstance(
            v, (int, float, np.integer, np.floating)) for v in items):
        raise InputDataError(f"{label} must be {n} numbers, got {value!r}")
    try:
        out = tuple(float(v) for v in items)
    except OverflowError:
        raise InputDataError(f"{label} must be {n} finite numbers, got {value!r}") from None
    if not all(math.isfinite(v) for v in out):
        raise InputDataError(f"{label} must be {n} finite numbers, got {value!r}")
    return out


def _box(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def paper_scenario(name: str) -> Scenario:
    """One of :data:`PAPER_SCENARIOS` (raises :class:`InputDataError` otherwise)."""
    if name == "simple":
        world = PolygonWorld((0.0, 0.0, 10.0, 10.0), (
            _box(2.6, 2.2, 3.8, 3.4),
            np.array([[5.2, 4.2], [6.6, 4.6], [6.8, 5.8], [5.6, 6.4], [4.8, 5.4]]),
            _box(2.0, 6.0, 3.2, 7.6),
            np.array([[7.0, 1.6], [8.6, 2.0], [7.6, 3.2]]),
            _box(7.2, 7.0, 8.0, 7.8),
        ), name="simple")
        return Scenario("simple", world, (1.0, 1.0, math.radians(30.0)), (9.0, 9.0))
    if name == "u-trap":
        # a U open toward the start (south), 3.2 wide inside, walls 0.4 thick
        u = np.array([[3.0, 4.5], [3.4, 4.5], [3.4, 7.1], [6.6, 7.1], [6.6, 4.5], [7.0, 4.5],
                      [7.0, 7.5], [3.0, 7.5]])
        world = PolygonWorld((0.0, 0.0, 10.0, 11.0), (u,), name="u-trap")
        return Scenario("u-trap", world, (5.0, 1.0, math.radians(90.0)), (5.0, 10.0))
    if name == "corridor":
        row = tuple(_box(x, 2.0, x + 0.6, 2.4) for x in (9.6, 10.5, 11.4, 12.3))
        world = PolygonWorld((0.0, 0.0, 16.0, 5.0), (_box(3.0, 2.0, 9.0, 2.4),) + row,
                             name="corridor")
        return Scenario("corridor", world, (1.0, 1.0, math.radians(20.0)), (15.0, 4.0))
    raise InputDataError(f"unknown reactive scenario {name!r}; choose one of "
                         f"{list(PAPER_SCENARIOS)}")


@dataclass(frozen=True)
class RandomSuiteParams:
    """How :func:`random_navigation_scenario` builds a cluttered world.

    Attributes:
        size: side of the square world.
        min_obstacles, max_obstacles: obstacle count range (placement may stop
            early if the world is full).
        min_radius, max_radius: radius range of each obstacle's circumscribed disc.
        gap: smallest free gap between discs and from discs to the walls;
            ``gap > 2 (radius + safety)`` of the robot guarantees a passage.
        endpoint_clearance: free space kept around start and goal (beyond the disc).
    """

    size: float = 10.0
    min_obstacles: int = 12
    max_obstacles: int = 18
    min_radius: float = 0.35
    max_radius: float = 1.0
    gap: float = 0.7
    endpoint_clearance: float = 0.8

    def __post_init__(self) -> None:
        for name in ("size", "min_radius", "max_radius", "gap", "endpoint_clearance"):
            require_positive("RandomSuiteParams", name, getattr(self, name))
        require_int("RandomSuiteParams", "min_obstacles", self.min_obstacles, 0)
        require_int("RandomSuiteParams", "max_obstacles", self.max_obstacles, self.min_obstacles)
        if self.max_radius < self.min_radius:
            raise ParameterError(f"RandomSuiteParams.max_radius must be >= min_radius, got "
                                 f"{self.max_radius!r} < {self.min_radius!r}")
        if self.size <= 2.0 * (self.gap + self.max_radius):
            raise ParameterError(f"RandomSuiteParams.size {self.size!r} is too small for "
                                 f"gap {self.gap!r} and max_radius {self.max_radius!r}")


def random_navigation_scenario(seed: int, params: RandomSuiteParams | None = None) -> Scenario:
    """A cluttered square world with start on the left, goal on the right (seeded)."""
    require_int("random_navigation_scenario", "seed", seed, 0, 2**63 - 1)
    p = params or RandomSuiteParams()
    rng = np.random.default_rng(seed)
    s = p.size
    margin = 0.1 * s
    start = np.array([margin, rng.uniform(margin, s - margin)])
    goal = np.array([s - margin, rng.uniform(margin, s - margin)])
    target = int(rng.integers(p.min_obstacles, p.max_obstacles + 1))
    centers: list[np.ndarray] = []
    radii: list[float] = []
    for _ in range(60 * max(target, 1)):
        if len(centers) >= target:
            break
        r = float(rng.uniform(p.min_radius, p.max_radius))
        c = rng.uniform(r + p.gap, s - r - p.gap, size=2)
        if min(np.hypot(*(c - start)), np.hypot(*(c - goal))) < r + p.endpoint_clearance:
            continue
        if any(np.hypot(*(c - c2)) < r + r2 + p.gap for c2, r2 in zip(centers, radii,
                                                                          strict=True)):
            continue
        centers.append(c)
        radii.append(r)
    obstacles = []
    for c, r in zip(centers, radii, strict=True):
        k = int(rng.integers(3, 8))
        ang = (np.arange(k) + rng.uniform(-0.3, 0.3, size=k)) * (2 * math.pi / k) \
            + rng.uniform(0, 2 * math.pi)
        obstacles.append(np.column_stack([c[0] + r * np.cos(ang), c[1] + r * np.sin(ang)]))
    world = PolygonWorld((0.0, 0.0, s, s), tuple(obstacles), name=f"random-{seed}")
    heading = math.atan2(goal[1] - start[1], goal[0] - start[0]) \
        + float(rng.uniform(-0.5 * math.pi, 0.5 * math.pi))
    return Scenario(f"random-{seed}", world, (float(start[0]), float(start[1]), heading),
                    (float(goal[0]), float(goal[1])))


def random_navigation_suite(n: int, seed: int,
                            params: RandomSuiteParams | None = None) -> list[Scenario]:
    """``n`` random scenarios; scenario ``i`` depends only on ``(seed, i)``."""
    require_int("random_navigation_suite", "n", n, 1, MAX_SUITE)
    require_int("random_navigation_suite", "seed", seed, 0, 2**63 - 1)
    seeds = np.random.SeedSequence(seed).spawn(n)
    return [random_navigation_scenario(int(ss.generate_state(1)[0]), params) for ss in seeds]


def _read_json(path: Path) -> Any:
    """A world or scenario file's JSON: UTF-8, at most the world reader's
    ``MAX_FILE_BYTES``, nested at most one level deeper than a world (a
    scenario wraps one), numbers finite; refused before parsing otherwise."""
    text = read_text(path, "scenario file", max_bytes=MAX_FILE_BYTES)
    return parse_json(text, str(path), max_depth=MAX_JSON_DEPTH + 1)


def resolve_world(text: str) -> tuple[PolygonWorld, Scenario | None]:
    """A world by name or path: a paper scenario, a built-in world, or a JSON file
    holding a world or a scenario.

    Returns the world and, for a paper scenario or a scenario file, the
    scenario (default start and goal).
    """
    if text in PAPER_SCENARIOS:
        sc = paper_scenario(text)
        return sc.world, sc
    if text in PolygonWorld.builtin_names():
        return PolygonWorld.builtin(text), None
    if text.endswith(".json") or Path(text).exists():
        path = Path(text)
        d = _read_json(path)
        try:
            if isinstance(d, dict) and "world" in d:
                sc = Scenario.from_dict(d)
                if not sc.name:
                    object.__setattr__(sc, "name", path.stem)
                return sc.world, sc
            world = world_from_dict(d)
        except InputDataError as exc:
            raise InputDataError(f"{path}: {exc}") from None
        if not world.name:
            object.__setattr__(world, "name", path.stem)
        return world, None
    raise InputDataError(f"unknown world {text!r}: give one of "
                         f"{list(PAPER_SCENARIOS) + PolygonWorld.builtin_names()} "
                         "or a JSON file path")
