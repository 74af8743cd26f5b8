"""Polygon worlds: a rectangular workspace with simple polygon obstacles.

A :class:`PolygonWorld` is validated when built (finite numbers, simple
non-degenerate polygons inside the bounds, obstacles neither overlapping nor
touching), stores every obstacle counter-clockwise, and answers the geometric
questions the planners ask: is a point free, is a segment free, how far is the
nearest wall. Segment tests are exact up to a tolerance of 1e-9 of the world's
size and run in numba (:mod:`._geometry_kernels`).

JSON form: ``{"bounds": [xmin, ymin, xmax, ymax], "obstacles": [[[x, y], ...], ...]}``
(an optional ``"name"``). Built-in worlds: :meth:`PolygonWorld.builtin`.

Decisions on awkward input (each tested):

* Coordinates must be real numbers (int or float, not bool, not strings such
  as ``"1.5"``) and finite; JSON ``NaN``/``Infinity`` are refused.
* A polygon with fewer than 3 vertices, zero area (all vertices collinear)
  or crossing edges is refused, naming the obstacle. Collinear consecutive
  vertices on an edge are accepted (a 180 deg corner).
* Two obstacles that overlap or touch (within :attr:`PolygonWorld.eps`) are
  refused, naming the pair: merge them into one polygon yourself. So the
  only zero-width gaps left are where an obstacle touches the outer
  boundary; every planner treats such a contact as closed (no path slips
  between the obstacle and the wall there).
* A start or goal on an obstacle's boundary is not free (the obstacles are
  closed sets); :meth:`PolygonWorld.check_point` says "on the boundary of".
* Size limits, checked before any quadratic work: at most
  :data:`MAX_VERTICES` obstacle vertices (derived from the memory of the
  planners' dense structures, :func:`planner_memory_bytes`); JSON files of at
  most :data:`MAX_FILE_BYTES` bytes, nested at most :data:`MAX_JSON_DEPTH`
  levels (checked on the text before parsing).

The world is immutable: every derived array is computed in ``__post_init__``
and read-only; the planners keep their graphs in their own caches.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, UnreachableError
from subtask_opt.base.files import parse_json
from subtask_opt.planners.polygon import _kernels as gk

# Relative length tolerance: contact closer than this fraction of the world size counts.
_REL_EPS = 1e-9

MEMORY_LIMIT_BYTES = 1 << 30
"""The planners' dense structures may take at most this much memory (1 GiB)."""

_MAKLINK_BYTES_PER_V2 = 320
"""MAKLINK's candidate links: about 4.5 V^2 candidates (vertex-vertex and vertex-wall
foot) of ~70 bytes each (end ids, length, sort order, wall masks); tracemalloc measured
a peak of 310 V^2 bytes on random worlds of 216 and 600 vertices."""


def planner_memory_bytes(n_vertices: int) -> dict[str, int]:
    """Estimated peak memory of each polygon planner's graph for ``n_vertices`` vertices.

    ``visibility``: the dense (V + 2)^2 float64 weight matrix and its
    distance and mask temporaries, 8 such matrices (tracemalloc measured 33 to
    64 V^2 bytes); ``maklink`` (also behind improved Dijkstra and PSO): the
    candidate links, which dominate.
    """
    v = int(n_vertices)
    return {"visibility": 8 * (v + 2) ** 2 * 8, "maklink": _MAKLINK_BYTES_PER_V2 * v * v}


def _max_vertices() -> int:
    v = 3
    while max(planner_memory_bytes(2 * v).values()) <= MEMORY_LIMIT_BYTES:
        v *= 2
    lo, hi = v, 2 * v  # bisection: lo fits, hi does not
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if max(planner_memory_bytes(mid).values()) <= MEMORY_LIMIT_BYTES \
            else (lo, mid)
    return lo


MAX_VERTICES = _max_vertices()
"""Most obstacle vertices a world may have: the largest V whose planner memory
(:func:`planner_memory_bytes`) fits in :data:`MEMORY_LIMIT_BYTES` (1831). MAKLINK
takes minutes at that size (9-15 s for 600 vertices, growing about as V^2.5)."""

MAX_COORDINATE = 1e9
"""Largest |x| or |y| a world accepts (metres or cells): products of coordinates
(areas, cross products) must stay far from overflow."""

MAX_FILE_BYTES = 8 * 1024 * 1024
"""Largest world JSON file read (8 MiB; MAX_VERTICES vertices take well under 1 MiB)."""

MAX_JSON_DEPTH = 8
"""Deepest bracket nesting accepted in a world file (a world needs 4)."""


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


def _seed003_listed() -> PolygonWorld:
    """seed003 with obstacle 0 in its listed vertex order: a bowtie (two triangles, top and
    bottom, meeting where its diagonals cross at (53, 219.5)), closed there by a waist
    0.1 m wide so that it stays one simple polygon."""
    x0, x1, y0, y1, cx, cy, d = 40.0, 66.0, 151.0, 288.0, 53.0, 219.5, 0.05
    bowtie = np.array([(x0, y1), (cx - d, cy), (x0, y0), (x1, y0), (cx + d, cy), (x1, y1)])
    rest = tuple(convex_hull(np.array(v, dtype=float)) for v in _SEED003_VERTICES[1:])
    return PolygonWorld(bounds=(0.0, 0.0, 350.0, 350.0), obstacles=(bowtie, *rest),
                        name="seed003-listed")


_BUILTINS = {"seed003": _seed003, "seed003-listed": _seed003_listed}


@dataclass(frozen=True)
class PolygonWorld:
    """A rectangular workspace with polygon obstacles (immutable).

    Attributes:
        bounds: ``(xmin, ymin, xmax, ymax)`` of the workspace.
        obstacles: one (k, 2) read-only float64 array per obstacle, k >= 3,
            stored counter-clockwise (clockwise input is reversed). A
            repeated closing vertex is dropped.
        name: a label for reports.

    Raises:
        InputDataError: non-numeric or non-finite coordinates, empty bounds,
            a polygon with fewer than 3 vertices, zero area or
            self-intersections, a polygon outside the bounds, two obstacles
            that overlap or touch (the message names the indices), or more
            than :data:`MAX_VERTICES` vertices in all.
    """

    bounds: tuple[float, float, float, float]
    obstacles: tuple[np.ndarray, ...]
    name: str = ""
    _verts: np.ndarray = field(init=False, repr=False, compare=False)
    _offsets: np.ndarray = field(init=False, repr=False, compare=False)
    _boxes: np.ndarray = field(init=False, repr=False, compare=False)
    _bounds_array: np.ndarray = field(init=False, repr=False, compare=False)
    _edges: np.ndarray = field(init=False, repr=False, compare=False)
    _boundary_edges: np.ndarray = field(init=False, repr=False, compare=False)
    _eps: float = field(init=False, repr=False, compare=False)
    _hash: int = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        bounds = _parse_bounds(self.bounds)
        if not isinstance(self.name, str):
            raise InputDataError(f"PolygonWorld.name must be a string, got {self.name!r}")
        if isinstance(self.obstacles, (str, bytes)) or (
                isinstance(self.obstacles, np.ndarray) and self.obstacles.ndim == 2):
            raise InputDataError("PolygonWorld.obstacles must be a sequence of (k, 2) "
                                 f"vertex lists, got {_short(self.obstacles)}")
        try:
            raw = list(self.obstacles)
        except TypeError:
            raise InputDataError("PolygonWorld.obstacles must be a sequence of polygons, "
                                 f"got {_short(self.obstacles)}") from None
        _check_vertex_count(raw)
        xmin, ymin, xmax, ymax = bounds
        eps = _REL_EPS * max(xmax - xmin, ymax - ymin)
        polys = tuple(_parse_polygon(i, p, eps) for i, p in enumerate(raw))

        sizes = [len(p) for p in polys]
        offsets = np.zeros(len(polys) + 1, dtype=np.int64)
        offsets[1:] = np.cumsum(sizes)
        verts = np.ascontiguousarray(np.concatenate(polys) if polys else np.zeros((0, 2)))
        boxes = np.array([[p[:, 0].min(), p[:, 1].min(), p[:, 0].max(), p[:, 1].max()]
                          for p in polys]).reshape(-1, 4)
        for i in range(len(polys)):
            if (boxes[i, 0] < xmin - eps or boxes[i, 2] > xmax + eps
                    or boxes[i, 1] < ymin - eps or boxes[i, 3] > ymax + eps):
                raise InputDataError(
                    f"obstacle {i} leaves the bounds {list(bounds)}: its vertices span "
                    f"x {boxes[i, 0]:g}..{boxes[i, 2]:g}, y {boxes[i, 1]:g}..{boxes[i, 3]:g}")
            if gk.self_contact(verts, offsets[i], offsets[i + 1], eps) >= 0:
                raise InputDataError(f"obstacle {i} is not a simple polygon (its edges "
                                     "intersect or fold back)")
        for i in range(len(polys)):
            for j in range(i + 1, len(polys)):
                if (boxes[i, 0] > boxes[j, 2] + eps or boxes[j, 0] > boxes[i, 2] + eps
                        or boxes[i, 1] > boxes[j, 3] + eps or boxes[j, 1] > boxes[i, 3] + eps):
                    continue
                if gk.polygons_meet(verts, offsets[i], offsets[i + 1],
                                    offsets[j], offsets[j + 1], eps):
                    raise InputDataError(
                        f"obstacles {i} and {j} overlap or touch; merge them into one "
                        "polygon (touching obstacles are refused)")

        rows = [np.hstack([p, np.roll(p, -1, axis=0)]) for p in polys]
        edges = np.concatenate(rows) if rows else np.zeros((0, 4))
        x0, y0, x1, y1 = bounds
        boundary = np.array([[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1],
                             [x0, y1, x0, y0]], dtype=float)
        bounds_array = np.array(bounds)
        for a in (verts, offsets, boxes, edges, boundary, bounds_array, *polys):
            a.flags.writeable = False
        for key, value in (("bounds", bounds), ("obstacles", polys), ("_verts", verts),
                           ("_offsets", offsets), ("_boxes", boxes), ("_edges", edges),
                           ("_boundary_edges", boundary), ("_bounds_array", bounds_array),
                           ("_eps", eps),
                           ("_hash", hash((bounds, self.name, verts.tobytes(),
                                           offsets.tobytes())))):
            object.__setattr__(self, key, value)

    # -- identity (arrays make the generated __eq__ ambiguous) -------------
    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PolygonWorld):
            return NotImplemented
        return (self._hash == other._hash and self.bounds == other.bounds
                and self.name == other.name and len(self.obstacles) == len(other.obstacles)
                and all(np.array_equal(a, b) for a, b in zip(self.obstacles, other.obstacles,
                                                               strict=True)))

    def __hash__(self) -> int:
        return self._hash

    # -- construction --------------------------------------------------------
    @classmethod
    def from_dict(cls, d: Any, *, name: str = "") -> PolygonWorld:
        """Build from ``{"bounds": [...], "obstacles": [[[x, y], ...], ...], "name"?: str}``.

        ``name`` is used when the dict has none.
        """
        if not isinstance(d, dict):
            raise InputDataError(f"a polygon world must be a JSON object, got {type(d).__name__}")
        missing = [k for k in ("bounds", "obstacles") if k not in d]
        if missing:
            raise InputDataError(f"polygon world is missing {', '.join(map(repr, missing))} "
                                 f"(keys present: {sorted(map(str, d))[:10]})")
        if not isinstance(d["obstacles"], (list, tuple)):
            raise InputDataError("polygon world 'obstacles' must be a list of polygons, got "
                                 f"{_short(d['obstacles'])}")
        if not isinstance(d["bounds"], (list, tuple)):
            raise InputDataError("polygon world 'bounds' must be a list of four numbers, got "
                                 f"{_short(d['bounds'])}")
        label = d.get("name", name) or name
        if not isinstance(label, str):
            raise InputDataError(f"polygon world 'name' must be a string, got {_short(label)}")
        return cls(bounds=tuple(d["bounds"]), obstacles=tuple(d["obstacles"]),  # type: ignore[arg-type]
                   name=label)

    def to_dict(self) -> dict[str, Any]:
        """The JSON form (see the module docstring)."""
        out: dict[str, Any] = {"bounds": list(self.bounds),
                               "obstacles": [p.tolist() for p in self.obstacles]}
        if self.name:
            out["name"] = self.name
        return out

    @classmethod
    def from_text(cls, text: str | bytes, *, name: str = "", source: str = "world") -> PolygonWorld:
        """Parse a world from JSON text (see :meth:`from_json` for the limits).

        Raises:
            InputDataError: too long, nested too deep, not JSON, NaN/Infinity,
                or not a valid world; the message starts with ``source``.
        """
        if isinstance(text, bytes):
            if len(text) > MAX_FILE_BYTES:
                raise InputDataError(f"{source}: {len(text)} bytes is over the limit of "
                                     f"{MAX_FILE_BYTES} bytes for a world file")
            try:
                text = text.decode("utf-8-sig")  # a leading byte-order mark is dropped
            except UnicodeDecodeError as exc:
                raise InputDataError(f"{source}: not UTF-8 text ({exc.reason} at byte "
                                     f"{exc.start})") from None
        if len(text) > MAX_FILE_BYTES:
            raise InputDataError(f"{source}: {len(text)} characters is over the limit of "
                                 f"{MAX_FILE_BYTES} for a world file")
        d = parse_json(text, source, max_depth=MAX_JSON_DEPTH)  # a world needs 4 levels
        try:
            return cls.from_dict(d, name=name)
        except InputDataError as exc:
            raise InputDataError(f"{source}: {exc}") from None

    @classmethod
    def from_json(cls, path: str | Path) -> PolygonWorld:
        """Read a world from a JSON file; its name defaults to the file's stem.

        Files over :data:`MAX_FILE_BYTES` bytes or nested deeper than
        :data:`MAX_JSON_DEPTH` are refused before parsing.

        Raises:
            OSError: the file cannot be read.
            InputDataError: the file is too large or malformed (the message names it).
        """
        from subtask_opt.base.files import read_bytes

        path = Path(path)
        data = read_bytes(path, "world file", max_bytes=MAX_FILE_BYTES)  # regular files only
        return cls.from_text(data, name=path.stem, source=str(path))

    def to_json(self, path: str | Path) -> None:
        """Write the world as JSON."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")

    @classmethod
    def builtin(cls, name: str) -> PolygonWorld:
        """A built-in world: ``"seed003"`` is the 350 x 350 benchmark of seed paper 003
        (its six obstacles taken as convex hulls); ``"seed003-listed"`` takes the first
        obstacle in its listed (self-crossing) vertex order, the reading to which a start
        and goal were fitted that give the paper's Table 1 (``benchmarks/maklink.py
        --search``)."""
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
        return self._eps

    @property
    def vertices(self) -> np.ndarray:
        """(n, 2) every obstacle vertex, obstacle after obstacle (read-only)."""
        return self._verts

    @property
    def offsets(self) -> np.ndarray:
        """(n_obstacles + 1,) obstacle i owns ``vertices[offsets[i]:offsets[i + 1]]``."""
        return self._offsets

    @property
    def edges(self) -> np.ndarray:
        """(m, 4) every obstacle edge as x1, y1, x2, y2 (counter-clockwise order)."""
        return self._edges

    @property
    def boundary_edges(self) -> np.ndarray:
        """(4, 4) the edges of the bounding box (bottom, right, top, left)."""
        return self._boundary_edges

    @property
    def on_bounds(self) -> np.ndarray:
        """(n,) bool over :attr:`vertices`: the vertex touches the outer boundary.

        Such a vertex closes the gap between its obstacle and the wall; a
        shortest path never bends there (the free angle on either side is
        below 180 deg), so the graph planners leave it out.
        """
        v, (x0, y0, x1, y1), e = self._verts, self.bounds, self._eps
        return ((np.abs(v[:, 0] - x0) <= e) | (np.abs(v[:, 0] - x1) <= e)
                | (np.abs(v[:, 1] - y0) <= e) | (np.abs(v[:, 1] - y1) <= e))

    def kernel_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
        """``(verts, offsets, boxes, bounds, eps)`` as the numba kernels take them."""
        return self._verts, self._offsets, self._boxes, self._bounds_array, self._eps

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
            InputDataError: p is not two finite real numbers.
            UnreachableError: p is outside the bounds, inside an obstacle or
                on an obstacle's boundary.
        """
        arr = _point_array(label, p)
        shown = f"({arr[0]:g}, {arr[1]:g})"
        if not self.in_bounds(arr):
            raise UnreachableError(f"{label} {shown} is outside the world bounds "
                                   f"{list(self.bounds)}")
        k = self.obstacle_at(arr)
        if k >= 0:
            verts, offsets, _, _, eps = self.kernel_arrays()
            where = ("on the boundary of" if gk.point_in_polygon(
                arr[0], arr[1], verts, offsets[k], offsets[k + 1], eps) == 0 else "inside")
            raise UnreachableError(f"{label} {shown} is {where} obstacle {k}")
        return arr

    def segment_free(self, p: Any, q: Any) -> bool:
        """The segment pq stays in the bounds and never enters an obstacle's interior.

        Touching vertices or sliding along edges is allowed, so shortest paths
        through vertices count as free; sliding along a wall past a point
        where an obstacle touches it is not.
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


def load_world(spec: str | Path) -> PolygonWorld:
    """A built-in world by name, or a world read from a ``.json`` file.

    Raises:
        InputDataError: neither a built-in name nor a .json path, or a malformed file.
        OSError: the file cannot be read.
    """
    text = str(spec)
    if text in _BUILTINS:
        return PolygonWorld.builtin(text)
    if not text.lower().endswith(".json"):
        raise InputDataError(f"world must be one of {sorted(_BUILTINS)} or a .json file, "
                             f"got {text!r}")
    return PolygonWorld.from_json(text)


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
    arr = _point_array("a point", p)
    return float(arr[0]), float(arr[1])


def _point_array(label: str, p: Any) -> np.ndarray:
    """p as a (2,) float array of finite real numbers, or InputDataError naming ``label``."""
    if isinstance(p, (str, bytes)):
        raise InputDataError(f"{label} must be two numbers x, y, got {_short(p)}")
    try:
        raw = np.asarray(p)
    except (TypeError, ValueError):
        raise InputDataError(f"{label} must be two numbers x, y, got {_short(p)}") from None
    if raw.dtype.kind not in "iuf":
        raise InputDataError(f"{label} must be two numbers x, y, got {_short(p)}")
    arr = raw.astype(float).reshape(-1)
    if arr.shape != (2,) or not np.all(np.isfinite(arr)):
        raise InputDataError(f"{label} must be two finite numbers x, y, got {_short(p)}")
    return arr


def _short(value: Any, limit: int = 60) -> str:
    """repr of ``value`` cut to ``limit`` characters (error messages stay one short line)."""
    try:
        text = repr(value)
    except Exception:  # noqa: BLE001 - a repr that fails must not hide the real error
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _real(value: Any) -> float | None:
    """A finite float from an int or float (numpy ones too); None for anything else."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        return None
    try:
        f = float(value)
    except OverflowError:  # an int too large for a float
        return None
    return f if math.isfinite(f) else None


def _parse_bounds(bounds: Any) -> tuple[float, float, float, float]:
    try:
        items = list(bounds) if not isinstance(bounds, (str, bytes)) else None
    except TypeError:
        items = None
    if items is None or len(items) != 4:
        raise InputDataError("PolygonWorld.bounds must be four numbers xmin, ymin, xmax, ymax, "
                             f"got {_short(bounds)}")
    b = tuple(_real(v) for v in items)
    if any(v is None for v in b):
        raise InputDataError("PolygonWorld.bounds must be four finite numbers xmin, ymin, xmax, "
                             f"ymax, got {_short(bounds)}")
    if any(abs(v) > MAX_COORDINATE for v in b):  # type: ignore[arg-type]
        raise InputDataError(f"PolygonWorld.bounds must lie within +-{MAX_COORDINATE:g}, "
                             f"got {list(b)}")
    if not (b[0] < b[2] and b[1] < b[3]):  # type: ignore[operator]
        raise InputDataError(
            f"PolygonWorld.bounds must have xmin < xmax and ymin < ymax, got {list(b)}")
    return b  # type: ignore[return-value]


def _check_vertex_count(raw: list[Any]) -> None:
    """Refuse more than MAX_VERTICES vertices before any per-vertex work."""
    total = 0
    for p in raw:
        try:
            total += len(p)
        except TypeError:
            continue  # not a sequence: _parse_polygon names it
    if total > MAX_VERTICES:
        need = max(planner_memory_bytes(total).values())
        raise InputDataError(
            f"the world has {total} obstacle vertices; the planners' dense graphs would need "
            f"about {need / 2**20:.0f} MiB, over the limit of {MEMORY_LIMIT_BYTES / 2**20:.0f} "
            f"MiB: at most {MAX_VERTICES} vertices")


def _parse_polygon(i: int, poly: Any, eps: float) -> np.ndarray:
    if isinstance(poly, np.ndarray):
        if poly.dtype.kind not in "iuf":
            raise InputDataError(f"obstacle {i} must hold numbers, got dtype {poly.dtype}")
        p = poly.astype(float)
    else:
        if isinstance(poly, (str, bytes, dict)) or not hasattr(poly, "__len__"):
            raise InputDataError(f"obstacle {i} must be a list of [x, y] vertices, got "
                                 f"{_short(poly)}")
        rows = []
        for k, v in enumerate(poly):
            if isinstance(v, np.ndarray) and v.dtype.kind in "iuf":
                v = v.tolist()
            if not isinstance(v, (list, tuple)) or len(v) != 2:
                raise InputDataError(f"obstacle {i} vertex {k} must be a pair [x, y], got "
                                     f"{_short(v)}")
            x, y = _real(v[0]), _real(v[1])
            if x is None or y is None:
                raise InputDataError(f"obstacle {i} vertex {k} must be two finite numbers, got "
                                     f"{_short(v)}")
            rows.append((x, y))
        p = np.array(rows, dtype=float).reshape(-1, 2)
    if p.ndim != 2 or p.shape[1] != 2:
        raise InputDataError(
            f"obstacle {i} must be a (k, 2) list of [x, y] vertices, got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise InputDataError(f"obstacle {i} has a non-finite coordinate")
    if np.abs(p).max(initial=0.0) > MAX_COORDINATE:
        raise InputDataError(f"obstacle {i} has a coordinate beyond +-{MAX_COORDINATE:g}: "
                             f"{np.abs(p).max():g}")
    if len(p) >= 2 and np.allclose(p[0], p[-1], rtol=0.0, atol=eps):
        p = p[:-1]  # an explicitly closed ring
    if len(p) < 3:
        raise InputDataError(f"obstacle {i} needs at least 3 vertices, got {len(p)}")
    area = signed_area(p)
    extent = float(np.max(np.ptp(p, axis=0)))
    if abs(area) <= eps * max(extent, eps):
        raise InputDataError(f"obstacle {i} is degenerate (area {abs(area):g}: its vertices "
                             "are collinear)")
    if area < 0:
        p = p[::-1]
    return np.ascontiguousarray(p)


