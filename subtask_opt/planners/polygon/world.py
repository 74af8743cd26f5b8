"""Polygon worlds: a rectangular workspace with simple polygon obstacles.

A :class:`PolygonWorld` is validated when built (finite numbers, simple
non-degenerate polygons inside the bounds, obstacles neither overlapping nor
touching), stores every obstacle counter-clockwise, and answers the geometric
questions the planners ask: is a point free, is a segment free, how far is the
nearest wall. Segment tests are exact up to a tolerance of 1e-9 of the world's
size and run in numba (:mod:`._geometry_kernels`).

JSON form: ``{"bounds": [xmin, ymin, xmax, ymax], "obstacles": [[[x, y], ...], ...]}``
(an optional ``"name"``). Built-in worlds: :meth:`PolygonWorld.builtin`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, UnreachableError
from subtask_opt.planners.polygon import _kernels as gk

# Relative length tolerance: contact closer than this fraction of the world size counts.
_REL_EPS = 1e-9


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull of (n, 2) points (Andrew's monotone chain)."""
    pts = np.unique(np.asarray(points, dtype=float), axis=0)  # sorted by x, then y
    if len(pts) < 3:
        return pts

    def chain(seq: np.ndarray) -> list[np.ndarray]:
        out: list[np.ndarray] = []
        for p in seq:
            while len(out) >= 2 and _cross(out[-2], out[-1], p) <= 0:
                out.pop()
            out.append(p)
        return out

    lower = chain(pts)
    upper = chain(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def _cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def signed_area(poly: np.ndarray) -> float:
    """Shoelace area of a polygon, positive when counter-clockwise."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


# The six obstacles of seed paper 003 (its Fig. 1), as listed; the world uses their hulls.
_SEED003_VERTICES = (
    ((40, 288), (66, 288), (40, 151), (66, 151)),
    ((115, 275), (95, 214), (123, 163), (170, 245)),
    ((90, 106), (90, 45), (183, 45), (183, 106)),
    ((238, 311), (212, 248), (274, 268)),
    ((258, 205), (234, 190), (234, 111), (296, 111), (296, 137)),
    ((170, 170), (190, 150), (210, 170)),
)


def _seed003() -> PolygonWorld:
    hulls = tuple(convex_hull(np.array(v, dtype=float)) for v in _SEED003_VERTICES)
    return PolygonWorld(bounds=(0.0, 0.0, 350.0, 350.0), obstacles=hulls, name="seed003")


_BUILTINS = {"seed003": _seed003}


@dataclass(frozen=True)
class PolygonWorld:
    """A rectangular workspace with polygon obstacles.

    Attributes:
        bounds: ``(xmin, ymin, xmax, ymax)`` of the workspace.
        obstacles: one (k, 2) float64 array per obstacle, k >= 3, stored
            counter-clockwise (clockwise input is reversed). A repeated
            closing vertex is dropped.
        name: a label for reports.

    Raises:
        InputDataError: non-finite numbers, empty bounds, a polygon with fewer
            than 3 vertices, zero area or self-intersections, a polygon
            outside the bounds, or two obstacles that overlap or touch; the
            message names the obstacle index.
    """

    bounds: tuple[float, float, float, float]
    obstacles: tuple[np.ndarray, ...]
    name: str = ""
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        bounds = _parse_bounds(self.bounds)
        object.__setattr__(self, "bounds", bounds)
        if isinstance(self.obstacles, np.ndarray) and self.obstacles.ndim == 2:
            raise InputDataError(
                "PolygonWorld.obstacles must be a sequence of (k, 2) arrays, got one 2-D array")
        try:
            raw = list(self.obstacles)
        except TypeError:
            raise InputDataError(
                f"PolygonWorld.obstacles must be a sequence of polygons, got {self.obstacles!r}"
            ) from None
        xmin, ymin, xmax, ymax = bounds
        eps = _REL_EPS * max(xmax - xmin, ymax - ymin)
        polys = tuple(_parse_polygon(i, p, eps) for i, p in enumerate(raw))
        object.__setattr__(self, "obstacles", polys)
        object.__setattr__(self, "name", str(self.name))

        sizes = [len(p) for p in polys]
        offsets = np.zeros(len(polys) + 1, dtype=np.int64)
        offsets[1:] = np.cumsum(sizes)
        verts = np.concatenate(polys) if polys else np.zeros((0, 2))
        boxes = np.array([[p[:, 0].min(), p[:, 1].min(), p[:, 0].max(), p[:, 1].max()]
                          for p in polys]).reshape(-1, 4)
        for i in range(len(polys)):
            if gk.self_contact(verts, offsets[i], offsets[i + 1], eps) >= 0:
                raise InputDataError(f"obstacle {i} is not a simple polygon (its edges "
                                     "intersect or fold back)")
            if (boxes[i, 0] < xmin - eps or boxes[i, 2] > xmax + eps
                    or boxes[i, 1] < ymin - eps or boxes[i, 3] > ymax + eps):
                raise InputDataError(
                    f"obstacle {i} leaves the bounds {list(bounds)}: its vertices span "
                    f"x {boxes[i, 0]:g}..{boxes[i, 2]:g}, y {boxes[i, 1]:g}..{boxes[i, 3]:g}")
        for i in range(len(polys)):
            for j in range(i + 1, len(polys)):
                if (boxes[i, 0] > boxes[j, 2] + eps or boxes[j, 0] > boxes[i, 2] + eps
                        or boxes[i, 1] > boxes[j, 3] + eps or boxes[j, 1] > boxes[i, 3] + eps):
                    continue
                if gk.polygons_meet(verts, offsets[i], offsets[i + 1],
                                    offsets[j], offsets[j + 1], eps):
                    raise InputDataError(f"obstacles {i} and {j} overlap or touch")

        for a in (verts, boxes, offsets):
            a.flags.writeable = False
        for p in polys:
            p.flags.writeable = False
        self._cache.update(verts=verts, offsets=offsets, boxes=boxes, eps=eps,
                           bounds_array=np.array(bounds))

    # -- identity (arrays make the generated __eq__ ambiguous) -------------
    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PolygonWorld):
            return NotImplemented
        return (self.bounds == other.bounds and self.name == other.name
                and len(self.obstacles) == len(other.obstacles)
                and all(np.array_equal(a, b) for a, b in zip(self.obstacles, other.obstacles,
                                                               strict=True)))

    def __hash__(self) -> int:
        return hash((self.bounds, self.name, self._cache["verts"].tobytes()))

    # -- construction --------------------------------------------------------
    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> PolygonWorld:
        """Build from ``{"bounds": [...], "obstacles": [[[x, y], ...], ...], "name"?: str}``."""
        if not isinstance(d, dict):
            raise InputDataError(f"a polygon world must be a JSON object, got {type(d).__name__}")
        missing = [k for k in ("bounds", "obstacles") if k not in d]
        if missing:
            raise InputDataError(f"polygon world is missing {', '.join(map(repr, missing))} "
                                 f"(keys present: {sorted(d)})")
        if not isinstance(d["obstacles"], (list, tuple)):
            raise InputDataError(
                f"polygon world 'obstacles' must be a list of polygons, got {d['obstacles']!r}")
        return cls(bounds=d["bounds"], obstacles=tuple(d["obstacles"]), name=d.get("name", ""))

    def to_dict(self) -> dict[str, Any]:
        """The JSON form (see the module docstring)."""
        out: dict[str, Any] = {"bounds": list(self.bounds),
                               "obstacles": [p.tolist() for p in self.obstacles]}
        if self.name:
            out["name"] = self.name
        return out

    @classmethod
    def from_json(cls, path: str | Path) -> PolygonWorld:
        """Read a world from a JSON file (OSError if unreadable, InputDataError if malformed)."""
        path = Path(path)
        text = path.read_text()
        try:
            d = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InputDataError(f"{path}: not valid JSON ({exc})") from None
        try:
            world = cls.from_dict(d)
        except InputDataError as exc:
            raise InputDataError(f"{path}: {exc}") from None
        if not world.name:
            object.__setattr__(world, "name", path.stem)
        return world

    def to_json(self, path: str | Path) -> None:
        """Write the world as JSON."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")

    @classmethod
    def builtin(cls, name: str) -> PolygonWorld:
        """A built-in world: ``"seed003"`` is the 350 x 350 benchmark of seed paper 003
        (its six obstacles taken as convex hulls)."""
        try:
            return _BUILTINS[name]()
        except KeyError:
            raise InputDataError(
                f"unknown built-in world {name!r}; choose one of {sorted(_BUILTINS)}") from None

    @staticmethod
    def builtin_names() -> list[str]:
        """Names accepted by :meth:`builtin`."""
        return sorted(_BUILTINS)

    # -- geometry ------------------------------------------------------------
    @property
    def eps(self) -> float:
        """Length tolerance of the geometric tests (1e-9 of the world size)."""
        return float(self._cache["eps"])

    @property
    def vertices(self) -> np.ndarray:
        """(n, 2) every obstacle vertex, obstacle after obstacle (read-only)."""
        return self._cache["verts"]

    @property
    def offsets(self) -> np.ndarray:
        """(n_obstacles + 1,) obstacle i owns ``vertices[offsets[i]:offsets[i + 1]]``."""
        return self._cache["offsets"]

    @property
    def edges(self) -> np.ndarray:
        """(m, 4) every obstacle edge as x1, y1, x2, y2 (counter-clockwise order)."""
        if "edges" not in self._cache:
            rows = [np.hstack([p, np.roll(p, -1, axis=0)]) for p in self.obstacles]
            e = np.concatenate(rows) if rows else np.zeros((0, 4))
            e.flags.writeable = False
            self._cache["edges"] = e
        return self._cache["edges"]

    @property
    def boundary_edges(self) -> np.ndarray:
        """(4, 4) the edges of the bounding box (bottom, right, top, left)."""
        if "boundary_edges" not in self._cache:
            x0, y0, x1, y1 = self.bounds
            e = np.array([[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1],
                          [x0, y1, x0, y0]], dtype=float)
            e.flags.writeable = False
            self._cache["boundary_edges"] = e
        return self._cache["boundary_edges"]

    def kernel_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
        """``(verts, offsets, boxes, bounds, eps)`` as the numba kernels take them."""
        c = self._cache
        return c["verts"], c["offsets"], c["boxes"], c["bounds_array"], c["eps"]

    def in_bounds(self, p: Any) -> bool:
        """Whether p lies in the closed bounding box."""
        x, y = _xy(p)
        x0, y0, x1, y1 = self.bounds
        e = self.eps
        return x0 - e <= x <= x1 + e and y0 - e <= y <= y1 + e

    def obstacle_at(self, p: Any) -> int:
        """Index of the obstacle whose closed area contains p, else -1."""
        x, y = _xy(p)
        verts, offsets, boxes, _, eps = self.kernel_arrays()
        return int(gk.obstacle_at(x, y, verts, offsets, boxes, eps))

    def is_free(self, p: Any) -> bool:
        """p is inside the bounds and in no obstacle (an obstacle's boundary is not free)."""
        return self.in_bounds(p) and self.obstacle_at(p) < 0

    def check_point(self, label: str, p: Any) -> np.ndarray:
        """Return p as a float array, or raise naming ``label`` and the value.

        Raises:
            InputDataError: p is not two finite numbers.
            UnreachableError: p is outside the bounds or inside (or on) an obstacle.
        """
        try:
            arr = np.asarray(p, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputDataError(f"{label} must be two numbers x, y, got {p!r}") from None
        if arr.shape != (2,) or not np.all(np.isfinite(arr)):
            raise InputDataError(f"{label} must be two finite numbers x, y, got {p!r}")
        shown = f"({arr[0]:g}, {arr[1]:g})"
        if not self.in_bounds(arr):
            raise UnreachableError(f"{label} {shown} is outside the world bounds "
                                   f"{list(self.bounds)}")
        k = self.obstacle_at(arr)
        if k >= 0:
            raise UnreachableError(f"{label} {shown} is inside obstacle {k}")
        return arr

    def segment_free(self, p: Any, q: Any) -> bool:
        """The segment pq stays in the bounds and never enters an obstacle's interior.

        Touching vertices or sliding along edges is allowed, so shortest paths
        through vertices count as free.
        """
        px, py = _xy(p)
        qx, qy = _xy(q)
        verts, offsets, boxes, bounds, eps = self.kernel_arrays()
        return bool(gk.segment_free(px, py, qx, qy, verts, offsets, boxes, bounds, eps))

    def path_free(self, path: np.ndarray) -> bool:
        """Every segment of a (k, 2) polyline is free (see :meth:`segment_free`)."""
        path = np.asarray(path, dtype=float)
        if len(path) == 1:
            return self.is_free(path[0])
        return all(self.segment_free(path[i], path[i + 1]) for i in range(len(path) - 1))

    def distance_to_obstacles(self, p: Any) -> float:
        """Distance from p to the nearest obstacle edge or boundary edge."""
        x, y = _xy(p)
        d = gk.distance_to_edges(x, y, self.boundary_edges)
        if len(self.obstacles):
            d = min(d, gk.distance_to_edges(x, y, self.edges))
        return float(d)


def interior_point(poly: np.ndarray) -> np.ndarray:
    """A point strictly inside a simple counter-clockwise polygon.

    At a convex corner v (neighbours u, w): the centroid of triangle u v w if
    no other vertex lies in it, else the midpoint of v and the vertex inside
    nearest to v's side (the classic ear argument).
    """
    n = len(poly)
    for i in range(n):
        u, v, w = poly[i - 1], poly[i], poly[(i + 1) % n]
        if _cross(u, v, w) <= 0:
            continue
        inside = [poly[j] for j in range(n) if j not in ((i - 1) % n, i, (i + 1) % n)
                  and _cross(u, v, poly[j]) > 0 and _cross(v, w, poly[j]) > 0
                  and _cross(w, u, poly[j]) > 0]
        if not inside:
            return (u + v + w) / 3.0
        d = [abs(_cross(u, w, q)) for q in inside]  # distance from the line uw, scaled
        return 0.5 * (v + inside[int(np.argmin(d))])
    raise InputDataError("polygon has no convex corner")  # pragma: no cover (simple polygons do)


def same_homotopy(world: PolygonWorld, path_a: np.ndarray, path_b: np.ndarray) -> bool:
    """Whether two free paths with the same end points pass every obstacle on the same side.

    The closed loop ``path_a`` + reversed ``path_b`` must wind zero times
    around a point inside each obstacle (paths never enter an obstacle, so
    that point is never on the loop).
    """
    loop = np.vstack([np.asarray(path_a, dtype=float), np.asarray(path_b, dtype=float)[::-1]])
    for poly in world.obstacles:
        c = interior_point(poly)
        d = loop - c
        ang = np.arctan2(d[:, 1], d[:, 0])
        turn = np.diff(np.append(ang, ang[0]))
        turn = (turn + np.pi) % (2 * np.pi) - np.pi
        if abs(turn.sum()) > np.pi:
            return False
    return True


def _xy(p: Any) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in np.asarray(p, dtype=float).reshape(-1))
    except (TypeError, ValueError):
        raise InputDataError(f"a point must be two numbers x, y, got {p!r}") from None
    return x, y


def _parse_bounds(bounds: Any) -> tuple[float, float, float, float]:
    try:
        b = tuple(float(v) for v in bounds)
    except (TypeError, ValueError):
        raise InputDataError(
            f"PolygonWorld.bounds must be four numbers xmin, ymin, xmax, ymax, got {bounds!r}"
        ) from None
    if len(b) != 4 or not all(math.isfinite(v) for v in b):
        raise InputDataError(
            f"PolygonWorld.bounds must be four finite numbers xmin, ymin, xmax, ymax, "
            f"got {bounds!r}")
    if not (b[0] < b[2] and b[1] < b[3]):
        raise InputDataError(
            f"PolygonWorld.bounds must have xmin < xmax and ymin < ymax, got {list(b)}")
    return b  # type: ignore[return-value]


def _parse_polygon(i: int, poly: Any, eps: float) -> np.ndarray:
    try:
        p = np.array(poly, dtype=float)
    except (TypeError, ValueError):
        raise InputDataError(f"obstacle {i} must be a list of [x, y] vertices, got {poly!r}"
                             ) from None
    if p.ndim != 2 or p.shape[1] != 2:
        raise InputDataError(
            f"obstacle {i} must be a (k, 2) list of [x, y] vertices, got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise InputDataError(f"obstacle {i} has a non-finite coordinate")
    if len(p) >= 2 and np.allclose(p[0], p[-1], rtol=0.0, atol=eps):
        p = p[:-1]  # an explicitly closed ring
    if len(p) < 3:
        raise InputDataError(f"obstacle {i} needs at least 3 vertices, got {len(p)}")
    area = signed_area(p)
    extent = float(np.max(np.ptp(p, axis=0)))
    if abs(area) <= eps * max(extent, eps):
        raise InputDataError(f"obstacle {i} is degenerate (area {abs(area):g})")
    if area < 0:
        p = p[::-1]
    return np.ascontiguousarray(p)
