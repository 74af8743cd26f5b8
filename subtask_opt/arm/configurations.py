"""Choosing one elbow configuration per subtask: the generalised TSP of a 2R arm.

Every subtask of a planar 2R arm can be reached elbow-down (0) or elbow-up (1)
(or only one of them within the joint limits). Under the ``joint`` and
``line`` time models the time of a leg depends on both ends' configurations,
given by :attr:`subtask_opt.arm.timing.models.TimingResult.branch_times` as an
(N, 2, N, 2) tensor. For a fixed cyclic order the best configurations follow
exactly from a dynamic programme (:func:`best_configurations`); the micro-GA
searches over orders and decodes each one this way
(:mod:`subtask_opt.arm._configuration_kernels`), so it optimises the order and the
configurations together.

Use it through ``SequencingProblem(..., time_model="joint",
configurations="optimize")``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from subtask_opt.arm import _configuration_kernels as _gc
from subtask_opt.base.errors import InputDataError, ParameterError


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


def pack_data(branch_times: Any) -> tuple[np.ndarray, float]:
    """The (N, 5N) ``data`` of :mod:`subtask_opt.arm._configuration_kernels`, and its penalty.

    Impossible legs (inf) become the finite :func:`penalty_for`, so the GA can
    rank tours that use them below every tour that does not.
    """
    t = _validated_tensor(branch_times)
    n = t.shape[0]
    penalty = penalty_for(t)
    safe = np.where(np.isfinite(t), t, penalty)
    data = np.empty((n, 5 * n))
    data[:, :n] = safe.min(axis=(1, 3))
    for ci in range(2):
        for cj in range(2):
            block = n + (2 * ci + cj) * n
            data[:, block:block + n] = safe[:, ci, :, cj]
    np.fill_diagonal(data[:, :n], 0.0)
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


__all__ = ["best_configurations", "gather", "induced_matrix", "pack_data", "penalty_for"]
