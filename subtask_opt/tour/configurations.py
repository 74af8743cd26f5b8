"""Choosing one elbow configuration per subtask: the generalised TSP of a 2R arm.

Every subtask of a planar 2R arm can be reached elbow-down (0) or elbow-up (1)
(or only one of them within the joint limits). Under the ``joint`` and
``line`` time models the time of a leg depends on both ends' configurations,
given by :attr:`subtask_opt.arm.timing.models.TimingResult.branch_times` as an
(N, 2, N, 2) tensor. For a fixed cyclic order the best configurations follow
exactly from a dynamic programme (:func:`best_configurations`); the micro-GA
searches over orders and decodes each one this way
(:mod:`subtask_opt.tour.clustered`), so it optimises the order and the
configurations together.

Use it through ``PlanarProblem(..., time_model="joint",
configurations="optimize")``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.tour import clustered as _gc
from subtask_opt.tour.clustered import ConfiguredData
from subtask_opt.tour.permutation import SEARCH_FAST, neighbour_table


def _validated_tensor(branch_times: Any) -> np.ndarray:
    t = np.asarray(branch_times, dtype=np.float64)
    if t.ndim != 4 or t.shape[1] != 2 or t.shape[3] != 2 or t.shape[0] != t.shape[2]:
        raise InputDataError(f"branch_times must have shape (N, 2, N, 2), got {t.shape}")
    if np.isnan(t).any() or (t < 0).any():
        raise InputDataError("branch_times must be >= 0 (inf where a leg is impossible), "
                             "got NaN or a negative time")
    return t


def penalty_for(branch_times: np.ndarray) -> float:
    """A finite stand-in for impossible legs, larger than any tour of possible legs.

    (N + 1) times the largest finite leg time (plus 1): one impossible leg costs
    more than every tour made only of possible ones.
    """
    finite = branch_times[np.isfinite(branch_times)]
    top = float(finite.max()) if finite.size else 1.0
    return (branch_times.shape[0] + 1) * top + 1.0


def pack_layers(legs: Any, offsets: Any, *, home_out: Any = None, home_in: Any = None,
                penalty: float | None = None, search: float = SEARCH_FAST) -> ConfiguredData:
    """The GA ``data`` of a generalised TSP over a flat configuration list.

    Args:
        legs: (M, M) leg times between configurations (inf: impossible).
        offsets: (N + 1,) target i owns configurations offsets[i] .. offsets[i+1]-1
            (every target at least one).
        home_out, home_in: (M,) times home -> configuration and configuration ->
            home; both None for a closed tour without home.
        penalty: the finite time that replaces inf (default :func:`penalty_for` of ``legs``).
        search: the operators' search mode (see :class:`ConfiguredData`).
    """
    m = np.asarray(legs, dtype=np.float64)
    off = np.asarray(offsets, dtype=np.int64)
    if m.ndim != 2 or m.shape[0] != m.shape[1]:
        raise InputDataError(f"legs must be a square (M, M) array, got shape {m.shape}")
    if off.ndim != 1 or off.size < 2 or off[0] != 0 or off[-1] != m.shape[0] or np.any(
            np.diff(off) < 1):
        raise InputDataError(f"offsets must rise strictly from 0 to M = {m.shape[0]}, "
                             f"got {off.tolist()[:10]}")
    if np.isnan(m).any() or (m < 0).any():
        raise InputDataError("legs must be >= 0 (inf where a leg is impossible)")
    if (home_out is None) != (home_in is None):
        raise ParameterError("home_out and home_in must both be given or both be None")
    n = off.size - 1
    if penalty is None:
        penalty = penalty_for_legs(m, n)
    safe = np.where(np.isfinite(m), m, penalty)
    if home_out is None:
        h_out = np.zeros(0)
        h_in = np.zeros(0)
    else:
        h_out = np.where(np.isfinite(home_out), np.asarray(home_out, np.float64), penalty)
        h_in = np.where(np.isfinite(home_in), np.asarray(home_in, np.float64), penalty)
        if h_out.shape != (m.shape[0],) or h_in.shape != (m.shape[0],):
            raise InputDataError(f"home_out and home_in must have shape ({m.shape[0]},)")
    # cheapest time between targets: min over rows of each block, then over columns
    row_min = np.minimum.reduceat(safe, off[:-1], axis=0)
    dist = np.minimum.reduceat(row_min, off[:-1], axis=1)
    np.fill_diagonal(dist, 0.0)
    # row_min[v, c]: the cheapest leg from any configuration of target v into c, which for
    # symmetric legs (the only ones the relocations that read it see) is ``cheapest``
    return ConfiguredData(np.ascontiguousarray(dist), off, np.ascontiguousarray(safe),
                          np.ascontiguousarray(h_out), np.ascontiguousarray(h_in),
                          float(search), cheapest=np.ascontiguousarray(row_min))


def penalty_for_legs(legs: np.ndarray, n_targets: int) -> float:
    """(N + 2) times the largest finite leg (plus 1): one impossible leg costs more than
    every tour (with home: N + 1 legs) made only of possible ones."""
    finite = legs[np.isfinite(legs)]
    top = float(finite.max()) if finite.size else 1.0
    return (n_targets + 2) * top + 1.0


def pack_data(branch_times: Any, neighbours: int = 8) -> tuple[ConfiguredData, float]:
    """The GA ``data`` (:class:`ConfiguredData`) of a 2R arm's branch times, and its penalty.

    Configuration ``2 i + c`` is subtask i on branch c. Impossible legs (inf)
    become the finite :func:`penalty_for`, so the GA can rank tours that use
    them below every tour that does not. Symmetric legs (the joint and line models
    of a closed tour) get ``neighbours`` nearest targets each (``data.near``): the
    search then relocates targets across configurations and kicks the tour.
    """
    t = _validated_tensor(branch_times)
    n = t.shape[0]
    penalty = penalty_for(t)
    legs = t.reshape(2 * n, 2 * n)
    data = pack_layers(legs, np.arange(0, 2 * n + 1, 2), penalty=penalty)
    if n > 1 and np.array_equal(data.legs, data.legs.T):
        data = data._replace(near=neighbour_table(data.dist, neighbours))
    return data, penalty


def best_configurations(order: Any, branch_times: Any) -> tuple[float, np.ndarray]:
    """Exact best configuration of each subtask for the closed tour ``order``.

    Args:
        order: a permutation of 0..N-1 (the cyclic visiting order).
        branch_times: (N, 2, N, 2) leg times ``[i, ci, j, cj]`` (inf: impossible).

    Returns:
        ``(tour_time, configurations)``: the minimum total time over all
        2**N configuration choices (inf if every choice needs an impossible
        leg) and the (N,) int64 configurations, indexed by subtask.
    """
    t = _validated_tensor(branch_times)
    n = t.shape[0]
    o = np.asarray(order)
    if o.shape != (n,) or not np.array_equal(np.sort(o), np.arange(n)):
        raise ParameterError(f"order must be a permutation of 0..{n - 1}, got {order!r}")
    data, penalty = pack_data(t)
    configs = np.zeros(n, dtype=np.int64)
    cost = float(_gc.decode(o.astype(np.int64), n, data, configs))
    legs = t[o, configs[o], np.roll(o, -1), configs[np.roll(o, -1)]]
    return (float(legs.sum()) if cost < penalty else float("inf")), configs


def gather(tensor: np.ndarray, configurations: Any) -> np.ndarray:
    """(N, N) entries ``tensor[i, c[i], j, c[j]]`` of an (N, 2, N, 2) array."""
    c = np.asarray(configurations, dtype=np.int64)
    idx = np.arange(len(c))
    return tensor[idx[:, None], c[:, None], idx[None, :], c[None, :]]


def induced_matrix(branch_times: Any, configurations: Any) -> np.ndarray:
    """(N, N) leg times for fixed configurations, zero diagonal."""
    m = gather(_validated_tensor(branch_times), configurations)
    np.fill_diagonal(m, 0.0)
    return m


def configuration_graph(branch_times: Any, present: Any
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The generalised TSP as a graph over the nodes that exist.

    Args:
        branch_times: (N, K, N, K) costs ``[i, ci, j, cj]``.
        present: (N, K) bool, which nodes exist (for an arm: the configurations within
            the joint limits).

    Returns:
        ``(cost, cluster, node)``: the (M, M) costs between the M present nodes (zero
        between two of one cluster), and each node's cluster and index in it, grouped by
        cluster in index order (what :func:`subtask_opt.tour.exact.gtsp_optimum` takes).
    """
    t = _validated_tensor(branch_times)
    mask = np.asarray(present, dtype=bool)
    if mask.shape != t.shape[:2]:
        raise ParameterError(f"present must have shape {t.shape[:2]}, got {mask.shape}")
    subtask, configuration = np.nonzero(mask)
    cost = t[subtask[:, None], configuration[:, None], subtask[None, :], configuration[None, :]]
    cost[subtask[:, None] == subtask[None, :]] = 0.0
    return cost, subtask, configuration


__all__ = ["ConfiguredData", "best_configurations", "configuration_graph", "gather",
           "induced_matrix", "pack_data", "pack_layers", "penalty_for", "penalty_for_legs"]
