"""Numba helpers shared by the dense-graph searches of several planner families."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def nearest_unsettled(dist, done):
    """Index of the unsettled node of least finite distance, or -1 if none is left:
    the selection step of the O(n^2) array Dijkstra, which beats a heap on dense graphs."""
    u = -1
    best = np.inf
    for v in range(dist.shape[0]):
        if not done[v] and dist[v] < best:
            best = dist[v]
            u = v
    return u
