"""Plane geometry every family uses: polyline length, turns, angle wrap, simplification."""

from __future__ import annotations

import math

import numpy as np


def wrap_angle(a: float | np.ndarray) -> float | np.ndarray:
    """Wrap an angle (or an array of angles) to ``[-pi, pi)``."""
    if isinstance(a, np.ndarray):
        return (a + np.pi) % (2.0 * np.pi) - np.pi
    return (float(a) + math.pi) % (2.0 * math.pi) - math.pi


def polyline_length(path: np.ndarray) -> float:
    """Euclidean length of a polyline given as a (k, 2) array."""
    path = np.asarray(path, dtype=float)
    if path.shape[0] < 2:
        return 0.0
    return float(np.sum(np.hypot(*np.diff(path, axis=0).T)))


def count_turns(path: np.ndarray, tol_deg: float = 1e-6) -> int:
    """Number of heading changes along a polyline (collinear points ignored)."""
    path = np.asarray(path, dtype=float)
    if path.shape[0] < 3:
        return 0
    d = np.diff(path, axis=0)
    d = d[np.hypot(d[:, 0], d[:, 1]) > 0]
    if d.shape[0] < 2:
        return 0
    cross = d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0]
    dot = np.sum(d[:-1] * d[1:], axis=1)
    angles = np.degrees(np.abs(np.arctan2(cross, dot)))
    return int(np.count_nonzero(angles > tol_deg))


def simplify(path: np.ndarray, tol: float = 0.05) -> np.ndarray:
    """Ramer-Douglas-Peucker: drop points within ``tol`` cells of the chord
    (a driven trajectory has a point per step; turns are counted on this)."""
    path = np.asarray(path, dtype=float)
    if path.shape[0] < 3:
        return path.copy()
    keep = np.zeros(path.shape[0], dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, path.shape[0] - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        a, b = path[i], path[j]
        ab = b - a
        n = math.hypot(*ab)
        seg = path[i + 1:j] - a
        if n == 0:
            d = np.hypot(seg[:, 0], seg[:, 1])
        else:
            d = np.abs(ab[0] * seg[:, 1] - ab[1] * seg[:, 0]) / n
        k = int(np.argmax(d))
        if d[k] > tol:
            keep[i + 1 + k] = True
            stack.extend([(i, i + 1 + k), (i + 1 + k, j)])
    return path[keep]
