"""Independent oracles for the grid planner tests (and tests of the oracles).

Line of sight by Liang-Barsky clipping against each blocked cell's closed
square, in floats: the touching cases (t_enter == t_exit) compare equal
rationals with small denominators, and IEEE division is correctly rounded,
so the comparisons are exact. Shortest paths by scipy's Dijkstra. The
"never through a blocked cell or a corner gap" rule by an exact supercover
walk in rational numbers (:func:`path_violations`).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra


def segment_touches_box(p0, p1, lo, hi) -> bool:
    """Whether segment p0-p1 meets the closed box [lo, hi] (Liang-Barsky)."""
    t0, t1 = 0.0, 1.0
    for axis in range(2):
        d = p1[axis] - p0[axis]
        if d == 0:
            if p0[axis] < lo[axis] or p0[axis] > hi[axis]:
                return False
            continue
        ta = (lo[axis] - p0[axis]) / d
        tb = (hi[axis] - p0[axis]) / d
        if ta > tb:
            ta, tb = tb, ta
        t0, t1 = max(t0, ta), min(t1, tb)
        if t0 > t1:
            return False
    return True


def los_free(occ: np.ndarray, a, b) -> bool:
    """Segment between cell centres a=(x, y), b touches no blocked closed square
    (Liang-Barsky against all blocked cells at once)."""
    ys, xs = np.nonzero(occ)
    if xs.size == 0:
        return True
    return not _meets_squares(xs, ys, a, b, closed=True)


def _meets_squares(xs, ys, a, b, *, closed: bool) -> bool:
    """Whether the segment a -> b meets any of the unit squares centred at (xs, ys):
    their closed squares, or (``closed=False``) their open ones (Liang-Barsky)."""
    p0 = np.asarray(a, dtype=float)
    d = np.asarray(b, dtype=float) - p0
    t0 = np.zeros(xs.size)
    t1 = np.ones(xs.size)
    inside = np.ones(xs.size, dtype=bool)
    for axis, c in ((0, xs), (1, ys)):
        lo, hi = c - 0.5, c + 0.5
        if d[axis] == 0:
            inside &= ((p0[axis] >= lo) & (p0[axis] <= hi) if closed
                       else (p0[axis] > lo) & (p0[axis] < hi))
            continue
        ta = (lo - p0[axis]) / d[axis]
        tb = (hi - p0[axis]) / d[axis]
        t0 = np.maximum(t0, np.minimum(ta, tb))
        t1 = np.minimum(t1, np.maximum(ta, tb))
    return bool(np.any(inside & ((t0 <= t1) if closed else (t0 < t1))))


def los_free_thesis(occ: np.ndarray, a, b) -> bool:
    """The thesis' rule (corner cutting) between cell centres a=(x, y), b: the segment
    meets no blocked cell's *open* square (Liang-Barsky with strict inequalities; cells
    outside the grid are blocked) and passes through no corner point shared by two
    blocked cells that touch diagonally (exact integer test on doubled coordinates)."""
    h, w = occ.shape
    pad = np.ones((h + 2, w + 2), dtype=bool)
    pad[1:-1, 1:-1] = occ
    ys, xs = np.nonzero(pad)
    xs, ys = xs - 1, ys - 1
    if _meets_squares(xs, ys, a, b, closed=False):
        return False
    # corner points (x + 1/2, y + 1/2), doubled, where two blocked cells touch diagonally
    corners = [(2 * x + 1, 2 * y + 1) for y in range(-1, h) for x in range(-1, w)
               if (pad[y + 1, x + 1] and pad[y + 2, x + 2])
               or (pad[y + 1, x + 2] and pad[y + 2, x + 1])]
    ax, ay, bx, by = (2 * int(v) for v in (*a, *b))
    for cx, cy in corners:
        on_line = (bx - ax) * (cy - ay) == (by - ay) * (cx - ax)
        if on_line and min(ax, bx) <= cx <= max(ax, bx) and min(ay, by) <= cy <= max(ay, by):
            return False
    return True


def los(occ: np.ndarray, a, b, corner_cutting: bool = False) -> bool:
    """:func:`los_free_thesis` with ``corner_cutting``, else :func:`los_free`."""
    return los_free_thesis(occ, a, b) if corner_cutting else los_free(occ, a, b)


def path_free(occ: np.ndarray, path) -> bool:
    pts = [tuple(map(float, p)) for p in path]
    return all(los_free(occ, pts[i], pts[i + 1]) for i in range(len(pts) - 1))


def octile_oracle(occ: np.ndarray, goal) -> np.ndarray:
    """8-connected distances (1, sqrt 2, no corner cutting) by scipy Dijkstra."""
    h, w = occ.shape
    rows, cols, vals = [], [], []
    for y in range(h):
        for x in range(w):
            if occ[y, x]:
                continue
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    nx, ny = x + dx, y + dy
                    if (dx, dy) == (0, 0) or not (0 <= nx < w and 0 <= ny < h) or occ[ny, nx]:
                        continue
                    if dx and dy and (occ[y, nx] or occ[ny, x]):
                        continue
                    rows.append(y * w + x)
                    cols.append(ny * w + nx)
                    vals.append(math.hypot(dx, dy))
    g = csr_matrix((vals, (rows, cols)), shape=(h * w, h * w))
    d = dijkstra(g, indices=goal[1] * w + goal[0])
    d = d.reshape(h, w)
    d[occ] = np.inf
    return d


def chamfer_oracle(occ: np.ndarray, goal, corner_cutting: bool = False) -> np.ndarray:
    """Jarvis' transform as the thesis describes it: raster sweeps with 3/4
    weights, repeated until nothing changes (result in cells, value / 3).
    ``corner_cutting``: a diagonal may pass one blocked side cell, not two."""
    h, w = occ.shape
    big = 10**9
    d = np.full((h, w), big, dtype=np.int64)
    d[goal[1], goal[0]] = 0
    changed = True
    while changed:
        changed = False
        for sweep in (1, -1):
            ys = range(h) if sweep == 1 else range(h - 1, -1, -1)
            for y in ys:
                xs = range(w) if sweep == 1 else range(w - 1, -1, -1)
                for x in xs:
                    if occ[y, x]:
                        continue
                    for dx in (-1, 0, 1):
                        for dy in (-1, 0, 1):
                            nx, ny = x + dx, y + dy
                            if (dx, dy) == (0, 0) or not (0 <= nx < w and 0 <= ny < h):
                                continue
                            if occ[ny, nx]:
                                continue
                            sides = int(occ[y, nx]) + int(occ[ny, x]) if dx and dy else 0
                            if sides == 2 or (sides == 1 and not corner_cutting):
                                continue
                            v = d[ny, nx] + (4 if dx and dy else 3)
                            if v < d[y, x]:
                                d[y, x] = v
                                changed = True
    out = np.where(d >= big, np.inf, d / 3.0)
    out[occ] = np.inf
    return out


def anyangle_oracle(occ: np.ndarray, goal, corner_cutting: bool = False) -> np.ndarray:
    """Dijkstra on the graph of every line-of-sight pair of free cell centres
    (``corner_cutting``: the thesis' rule, :func:`los_free_thesis`)."""
    h, w = occ.shape
    free = [(x, y) for y in range(h) for x in range(w) if not occ[y, x]]
    idx = {c: i for i, c in enumerate(free)}
    rows, cols, vals = [], [], []
    for i, a in enumerate(free):
        for j in range(i + 1, len(free)):
            b = free[j]
            if los(occ, a, b, corner_cutting):
                length = math.hypot(a[0] - b[0], a[1] - b[1])
                rows += [i, j]
                cols += [j, i]
                vals += [length, length]
    g = csr_matrix((vals, (rows, cols)), shape=(len(free), len(free)))
    d = dijkstra(g, indices=idx[tuple(goal)])
    out = np.full((h, w), np.inf)
    for (x, y), v in zip(free, d, strict=True):
        out[y, x] = v
    return out


def levels_oracle(occ: np.ndarray, goal, corner_cutting: bool = False) -> np.ndarray:
    """The thesis' MDT fill as printed (section 2.2.4), in plain Python: level 1
    = cells that see the goal, level k + 1 = empty cells that see a level-k cell,
    value = the least (level-k value + segment length); filled cells stay."""
    h, w = occ.shape
    free = [(x, y) for y in range(h) for x in range(w) if not occ[y, x]]
    value = {tuple(goal): 0.0}
    frontier = [tuple(goal)]
    while frontier:
        new = {}
        for c in free:
            if c in value:
                continue
            cands = [value[f] + math.hypot(c[0] - f[0], c[1] - f[1])
                     for f in frontier if los(occ, f, c, corner_cutting)]
            if cands:
                new[c] = min(cands)
        value.update(new)
        frontier = list(new)
    out = np.full((h, w), np.inf)
    for (x, y), v in value.items():
        out[y, x] = v
    return out


def _blocked(occ: np.ndarray, x: int, y: int) -> bool:
    h, w = occ.shape
    return not (0 <= x < w and 0 <= y < h) or bool(occ[y, x])


def _cells_at(v: Fraction) -> list[int]:
    """Cell indices whose closed interval [i - 1/2, i + 1/2] holds v."""
    lo = math.ceil(v - Fraction(1, 2))
    hi = math.floor(v + Fraction(1, 2))
    return list(range(lo, hi + 1))


def segment_violations(occ: np.ndarray, p, q) -> list[str]:
    """Where the straight move p -> q enters a blocked cell or passes between
    two blocked cells that touch at a corner (exact, in rationals).

    The move is split at every cell border it crosses; the middle of each
    piece must lie in a free cell (on a border: in at least one free cell).
    Where it crosses a cell corner diagonally, the two cells beside that
    corner must not both be blocked. Cells outside the grid are blocked.
    """
    p = [Fraction(float(v)) for v in p]
    q = [Fraction(float(v)) for v in q]
    d = [q[0] - p[0], q[1] - p[1]]
    ts = {Fraction(0), Fraction(1)}
    crossings: dict[Fraction, int] = {}
    for axis in range(2):
        if d[axis] == 0:
            continue
        lo, hi = sorted((p[axis], q[axis]))
        k = math.ceil(lo - Fraction(1, 2))
        while k + Fraction(1, 2) <= hi:
            t = (k + Fraction(1, 2) - p[axis]) / d[axis]
            if 0 < t < 1:
                ts.add(t)
                crossings[t] = crossings.get(t, 0) + 1
            k += 1
    out = []
    order = sorted(ts)
    for t0, t1 in zip(order[:-1], order[1:], strict=True):
        m = [p[a] + (t0 + t1) / 2 * d[a] for a in range(2)]
        cells = [(x, y) for x in _cells_at(m[0]) for y in _cells_at(m[1])]
        if all(_blocked(occ, x, y) for x, y in cells):
            out.append(f"enters blocked cell(s) {cells} at {[float(v) for v in m]}")
    for t, n in crossings.items():
        if n == 2:  # through a corner, diagonally
            c = [p[a] + t * d[a] for a in range(2)]
            a, b = int(c[0] - Fraction(1, 2)), int(c[1] - Fraction(1, 2))
            if (d[0] > 0) == (d[1] > 0):
                others = [(a + 1, b), (a, b + 1)]
            else:
                others = [(a, b), (a + 1, b + 1)]
            if all(_blocked(occ, x, y) for x, y in others):
                out.append(f"passes the corner gap at {[float(v) for v in c]} between {others}")
    return out


def path_violations(occ: np.ndarray, path) -> list[str]:
    """:func:`segment_violations` of every segment of a polyline (a single
    point: whether its cell is free)."""
    pts = [tuple(map(float, pt)) for pt in path]
    if len(pts) == 1:
        x, y = (round(v) for v in pts[0])
        return [f"point {pts[0]} is in a blocked cell"] if _blocked(occ, x, y) else []
    out = []
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        out.extend(segment_violations(occ, a, b))
    return out


# -- tests of the oracles themselves ------------------------------------------------
def test_box_touch_cases():
    box = ((0.5, -0.5), (1.5, 0.5))
    assert segment_touches_box((0, 0), (1, 1), *box)  # through the corner (0.5, 0.5)
    assert not segment_touches_box((0, 1), (1, 2), *box)
    assert segment_touches_box((0, 0), (2, 0), *box)


def test_oracles_agree_on_open_grid():
    occ = np.zeros((4, 5), dtype=bool)
    d8 = octile_oracle(occ, (0, 0))
    assert d8[3, 4] == pytest.approx(math.sqrt(2) * 3 + 1)
    assert chamfer_oracle(occ, (0, 0))[3, 4] == (4 * 3 + 3) / 3
    assert anyangle_oracle(occ, (0, 0))[3, 4] == 5.0


def test_violation_walk_cases():
    gap = np.array([[False, True], [True, False]])  # ".@" / "@."
    assert path_violations(gap, [(0, 0), (1, 1)])  # through the corner gap
    one = np.array([[False, True], [False, False]])
    assert path_violations(one, [(0, 0), (1, 1)]) == []  # passes one corner: allowed
    assert path_violations(one, [(0, 0), (1, 0)])  # into the blocked cell
    wall = np.zeros((3, 3), bool)
    wall[1, 1] = True
    assert path_violations(wall, [(0, 0), (2, 0), (2, 2)]) == []
    assert path_violations(wall, [(0, 0), (2, 2)])  # through the centre
    assert path_violations(wall, [(0.0, 0.5), (2.0, 0.5)]) == []  # along its border
    assert path_violations(wall, [(0, 0), (-1, 0)])  # off the grid


def test_corner_cutting_oracle():
    occ = np.array([[False, True], [False, False]])
    assert chamfer_oracle(occ, (0, 1))[0, 0] == 1.0
    assert chamfer_oracle(occ, (1, 1))[0, 0] == 2.0  # around the corner
    assert chamfer_oracle(occ, (1, 1), corner_cutting=True)[0, 0] == 4 / 3  # one diagonal
    gap = np.array([[False, True], [True, False]])
    assert chamfer_oracle(gap, (0, 0), corner_cutting=True)[1, 1] == np.inf
