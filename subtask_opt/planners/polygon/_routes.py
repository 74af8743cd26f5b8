"""Shared pieces of the graph planners: the one dense Dijkstra with its path
read-back, and the per-world graph cache.

Graphs depend on the (immutable, hashable) world alone, so each planner module
keeps a small LRU cache keyed by the world (its hash covers bounds, name and
every vertex; equal worlds share a graph). The world itself stays free of state.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache
from typing import TypeVar

import numpy as np

from subtask_opt.planners.polygon import _kernels as gk

GRAPH_CACHE_SIZE = 16
"""Worlds whose graphs each planner module keeps (least recently used dropped first)."""

F = TypeVar("F", bound=Callable[..., object])


def world_cache(fn: F) -> F:
    """Cache ``fn(world, ...)`` for the :data:`GRAPH_CACHE_SIZE` most recent arguments."""
    return lru_cache(maxsize=GRAPH_CACHE_SIZE)(fn)  # type: ignore[return-value]


def shortest_route(weights: np.ndarray, source: int, target: int) -> tuple[float, list[int]]:
    """Dijkstra on a dense (n, n) weight matrix (inf: no edge).

    Returns the length and the nodes from ``source`` to ``target`` inclusive,
    or ``(inf, [])`` when the target cannot be reached.
    """
    length, prev = gk.dijkstra_dense(np.ascontiguousarray(weights, dtype=float), source, target)
    if not math.isfinite(length):
        return math.inf, []
    nodes = [target]
    while nodes[-1] != source:
        nodes.append(int(prev[nodes[-1]]))
    return float(length), nodes[::-1]


def check_deterministic(planner: str, params: object, params_type: type | None,
                        seed: object, stop: object) -> None:
    """Refuse a seed or stopping criteria (and params of the wrong type) for a
    deterministic, non-iterative planner, naming the planner."""
    from subtask_opt.base.errors import ParameterError

    if seed is not None:
        raise ParameterError(f"{planner} is deterministic and takes no seed, got seed={seed!r}")
    if stop is not None:
        raise ParameterError(f"{planner} is not iterative and takes no stopping criteria, "
                             f"got stop={stop!r}")
    if params is not None and (params_type is None or not isinstance(params, params_type)):
        allowed = "None" if params_type is None else f"None or a {params_type.__name__}"
        raise ParameterError(f"{planner} params must be {allowed}, got {params!r}")


def same_point(world_eps: float, start: np.ndarray, goal: np.ndarray) -> bool:
    """Start and goal coincide (within the world's length tolerance)."""
    return math.hypot(goal[0] - start[0], goal[1] - start[1]) <= world_eps
