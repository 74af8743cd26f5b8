"""An independent collision oracle for AGV runs.

It reads only the recorded true trajectory (``run.times``, ``run.trajectory``)
and the scenario's own definitions (the obstacles' polylines, speeds and start
times; the world's blocked cells), never the simulator's flags, its recorded
obstacle positions or its separations:

* moving obstacles: between two recorded samples the AGV moves straight (the
  simulator turns a whole step at once) and an obstacle moves straight between
  its own kinks (its start, its polyline's vertices, its stop); the samples and
  the kinks cut time into pieces where both move straight, and on each piece the
  closest approach has a closed form, so the minimum over the whole run is exact;
* walls: the trajectory as a polyline against the union of the blocked cells'
  closed squares and the outside of the map (shapely, touching counts).
"""

from __future__ import annotations

import math

import numpy as np
from shapely.geometry import LineString, Point, box
from shapely.ops import unary_union


def obstacle_at(path: np.ndarray, speed: float, start_time: float, t: np.ndarray) -> np.ndarray:
    """Positions (len(t), 2) of an obstacle that waits at ``path[0]`` until
    ``start_time``, then follows ``path`` at ``speed`` and stays at its end."""
    path = np.asarray(path, dtype=float)
    t = np.asarray(t, dtype=float)
    if len(path) == 1:
        return np.repeat(path, len(t), axis=0)
    seg = np.hypot(*np.diff(path, axis=0).T)
    ends = np.concatenate([[0.0], np.cumsum(seg)])
    s = np.clip((t - start_time) * speed, 0.0, ends[-1])
    i = np.clip(np.searchsorted(ends, s, side="right") - 1, 0, len(seg) - 1)
    f = np.where(seg[i] > 0, (s - ends[i]) / np.where(seg[i] > 0, seg[i], 1.0), 0.0)
    return path[i] + f[:, None] * (path[i + 1] - path[i])


def _kinks(path: np.ndarray, speed: float, start_time: float) -> np.ndarray:
    seg = np.hypot(*np.diff(np.asarray(path, dtype=float), axis=0).T)
    return start_time + np.concatenate([[0.0], np.cumsum(seg)]) / speed


def min_obstacle_separation(scenario, times: np.ndarray, trajectory: np.ndarray
                            ) -> tuple[float, int, float]:
    """(least centre distance, obstacle, time of it) over the whole run;
    (inf, -1, nan) without obstacles."""
    times = np.asarray(times, dtype=float)
    traj = np.asarray(trajectory, dtype=float)
    best = (math.inf, -1, math.nan)
    for j, ob in enumerate(scenario.obstacles):
        path = np.asarray(ob.path, dtype=float)
        kinks = _kinks(path, ob.speed, ob.start_time)
        cuts = np.union1d(times, kinks[(kinks > times[0]) & (kinks < times[-1])])
        agv = np.column_stack([np.interp(cuts, times, traj[:, 0]),
                               np.interp(cuts, times, traj[:, 1])])
        rel = obstacle_at(path, ob.speed, ob.start_time, cuts) - agv
        if len(cuts) == 1:
            d, t = float(np.hypot(*rel[0])), float(cuts[0])
        else:
            r0, r1 = rel[:-1], rel[1:]
            dr = r1 - r0
            den = np.einsum("ij,ij->i", dr, dr)
            f = np.clip(-np.einsum("ij,ij->i", r0, dr) / np.where(den > 0, den, 1.0), 0, 1)
            closest = r0 + f[:, None] * dr
            dist = np.hypot(closest[:, 0], closest[:, 1])
            k = int(np.argmin(dist))
            d, t = float(dist[k]), float(cuts[k] + f[k] * (cuts[k + 1] - cuts[k]))
        if d < best[0]:
            best = (d, j, t)
    return best


def walls(occupancy: np.ndarray):
    """The blocked area of a grid world: the closed squares of its blocked
    cells and everything outside ``[-0.5, w - 0.5] x [-0.5, h - 0.5]``."""
    occ = np.asarray(occupancy, dtype=bool)
    h, w = occ.shape
    cells = [box(x - 0.5, y - 0.5, x + 0.5, y + 0.5) for y, x in zip(*np.nonzero(occ),
                                                                       strict=True)]
    outside = box(-10.5, -10.5, w + 9.5, h + 9.5).difference(box(-0.5, -0.5, w - 0.5, h - 0.5))
    return unary_union([*cells, outside])


def wall_clearance(occupancy: np.ndarray, trajectory: np.ndarray) -> float:
    """Least distance of the trajectory to the blocked area; 0 when it
    touches or enters it."""
    traj = np.asarray(trajectory, dtype=float)
    geom = Point(traj[0]) if len(traj) == 1 or np.all(traj == traj[0]) else LineString(traj)
    blocked = walls(occupancy)
    return 0.0 if geom.intersects(blocked) else float(geom.distance(blocked))
