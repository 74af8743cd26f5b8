"""The problems of the tour core: a cost matrix, and a clustered cost tensor.

Neither knows a robot: an arm problem (:class:`subtask_opt.arm.problem.ArmProblem`) compiles
into one of them. :class:`MatrixProblem` visits every node once; :class:`ClusteredProblem`
visits one node of every cluster (a generalised TSP: for an arm, a cluster is a target and
its nodes are the arm's configurations there). :func:`subtask_opt.tour.solve.solve` takes
either, with the tour shape and precedence of
:class:`~subtask_opt.tour.constraints.TourConstraints`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.tour.clustered import ConfiguredData


class _Sized:
    """What every tour problem says of its (N, N) ``matrix``."""

    matrix: np.ndarray

    @property
    def size(self) -> int:
        """Number of nodes (clusters of a clustered problem)."""
        return int(self.matrix.shape[0])

    @property
    def symmetric(self) -> bool:
        """Whether the costs are the same both ways."""
        return bool(np.allclose(self.matrix, self.matrix.T, rtol=1e-12, atol=0.0))


@dataclass(frozen=True)
class MatrixProblem(_Sized):
    """A tour over a travel-time matrix of your own (N x N, finite, >= 0).

    Attributes:
        matrix: the travel times (copied, read-only).
        first: index of the node the closed tour starts and ends at (default 0).
        allow_impossible: inf entries mark legs no tour may use (else every entry must
            be finite).
    """

    matrix: np.ndarray
    first: int | None = None
    allow_impossible: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.allow_impossible, bool):
            raise ParameterError(f"MatrixProblem.allow_impossible must be True or False, got "
                                 f"{self.allow_impossible!r}")
        impossible = None
        if self.allow_impossible:
            impossible = np.isinf(np.asarray(self.matrix, dtype=float))
        m = _validated_matrix(self.matrix, allow_inf=impossible)
        object.__setattr__(self, "matrix", m)
        _check_first(self.first, m.shape[0])

    def tour_time(self, order: np.ndarray) -> float:
        """Total time of the closed tour visiting ``order`` (validated)."""
        order = _validated_order(order, self.size)
        return float(np.sum(self.matrix[order, np.roll(order, -1)]))


@dataclass(frozen=True, eq=False)
class ClusteredProblem(_Sized):
    """One node of every cluster visited: a generalised TSP over a cost tensor.

    Attributes:
        costs: (N, K, N, K) cost from node k of cluster i to node l of cluster j
            (inf: impossible, or a node that does not exist); read-only copy.
        matrix: (N, N) costs of the methods that keep one node per cluster fixed (the
            canonical form of the constraints, the MILP certificate); default: the
            cheapest over node pairs.
        present: (N, K) which nodes exist (default: every node with a finite cost);
            the branch-and-cut certificate works on the present nodes only.
        first: the cluster the closed tour starts and ends at (default 0).

    Today the operators take K = 2 (the elbows of a planar arm); serial arms with many
    configurations per target build their :class:`ConfiguredData` directly.
    """

    costs: np.ndarray
    # None on construction: the cheapest node pairs / the nodes with a finite cost
    matrix: np.ndarray = None  # type: ignore[assignment]
    present: np.ndarray = None  # type: ignore[assignment]
    first: int | None = None
    _data: ConfiguredData = field(init=False, repr=False)

    def __post_init__(self) -> None:
        from subtask_opt.tour.configurations import _validated_tensor, pack_data

        t = _validated_tensor(self.costs)
        t.setflags(write=False)
        object.__setattr__(self, "costs", t)
        n = t.shape[0]
        if self.matrix is None:
            m = np.min(t, axis=(1, 3))
            np.fill_diagonal(m, 0.0)
        else:
            m = self.matrix
        excluded = np.isinf(m)
        object.__setattr__(self, "matrix", _validated_matrix(m, allow_inf=excluded))
        if self.present is None:
            present = np.isfinite(t).any(axis=(2, 3))
        else:
            present = np.asarray(self.present, dtype=bool)
            if present.shape != t.shape[:2]:
                raise ParameterError(f"ClusteredProblem.present must have shape "
                                     f"{t.shape[:2]}, got {present.shape}")
        present = present.copy()
        present.setflags(write=False)
        object.__setattr__(self, "present", present)
        _check_first(self.first, n)
        object.__setattr__(self, "_data", pack_data(t)[0])

    def configured_data(self) -> ConfiguredData:
        """The per-node costs the clustered GA decodes."""
        return self._data

    def decode(self, order: Any) -> tuple[float, np.ndarray]:
        """``(tour cost, nodes)``: the best node of every cluster for the closed tour ``order``."""
        from subtask_opt.tour.configurations import best_configurations

        return best_configurations(_validated_order(order, self.size), self.costs)

    def tour_time(self, order: Any) -> float:
        """Cost of the closed tour ``order`` at its best nodes."""
        return self.decode(order)[0]


TourProblem = MatrixProblem | ClusteredProblem
"""What :func:`subtask_opt.tour.solve.solve` takes."""


MAX_LEG_TIME = 1e9
"""The largest finite travel time a matrix may hold (sums of N of them stay exact enough)."""
MAX_NODES = 20_000
"""The most nodes a problem may have (dense N x N matrices)."""


def _validated_matrix(matrix: np.ndarray, allow_inf: np.ndarray | None = None) -> np.ndarray:
    try:
        raw = np.asarray(matrix)
        if raw.dtype.kind not in "iuf":
            raise TypeError
        m = np.array(raw, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InputDataError("travel-time matrix must hold real numbers") from None
    if m.ndim != 2 or m.shape[0] != m.shape[1]:
        raise InputDataError(f"travel-time matrix must be square, got shape {m.shape}")
    if m.shape[0] < 3:
        raise InputDataError(f"need at least 3 subtasks, got {m.shape[0]}")
    if m.shape[0] > MAX_NODES:
        raise InputDataError(f"the matrix has {m.shape[0]} nodes; the limit is {MAX_NODES}")
    bad = np.argwhere(~np.isfinite(m) & (True if allow_inf is None else ~allow_inf))
    if bad.size:
        i, j = bad[0]
        raise InputDataError(
            f"travel time from subtask {i} to {j} is {m[i, j]} (must be finite)")
    neg = np.argwhere(m < 0)
    if neg.size:
        i, j = neg[0]
        raise InputDataError(f"travel time from subtask {i} to {j} is negative ({m[i, j]})")
    big = np.argwhere(np.isfinite(m) & (m > MAX_LEG_TIME))
    if big.size:
        i, j = big[0]
        raise InputDataError(f"travel time from subtask {i} to {j} is {m[i, j]:g}; the limit "
                             f"is {MAX_LEG_TIME:g} (scale the matrix)")
    m.setflags(write=False)
    return m


def _check_first(first: object, n: int) -> None:
    if first is not None and (isinstance(first, bool) or not isinstance(first, (int, np.integer))
                              or not 0 <= first < n):
        raise ParameterError(f"first must be an index in [0, {n - 1}], got {first!r}")


def _validated_order(order: np.ndarray, n: int) -> np.ndarray:
    o = np.asarray(order)
    if o.shape != (n,) or not np.array_equal(np.sort(o), np.arange(n)):
        raise ParameterError(f"order must be a permutation of 0..{n - 1}, got {order!r}")
    return o.astype(np.int64)

