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

from subtask_opt.base.errors import InputDataError, ParameterError, require_int
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


@dataclass(frozen=True, eq=False)
class GtspProblem(_Sized):
    """One vertex of every set visited: a generalised TSP over a flat vertex matrix.

    The clustered problem of sets of any size (GTSPLIB's, up to hundreds of vertices a
    set): where :class:`ClusteredProblem` holds a dense (N, K, N, K) tensor padded to the
    largest cluster, this holds the (M, M) weights between the M vertices and the set of
    each vertex. :func:`subtask_opt.tour.solve.solve` searches it with the same clustered
    chromosome (order of the sets, the vertices decoded exactly by a layered shortest path).

    Attributes:
        weights: (M, M) cost from vertex u to vertex v (inf: a forbidden arc; the
            diagonal and the costs within a set are never used); read-only copy.
        sets: (M,) the set (0..N-1) of every vertex; every set holds a vertex.
        first: the set the closed tour starts and ends at (default 0).
        lns_steps: large-neighbourhood steps (remove and reinsert sets, GLNS-style, see
            :func:`subtask_opt.tour.clustered.large_neighbourhood_search`) every restart
            individual and child of the micro-GA gets; 0: the clustered chromosome's
            order search with vertex-choosing relocations and kicks (the arm problems'
            search); None: :data:`LNS_STEPS_PER_SET` per set.
        matrix: (N, N) the cheapest arc between each pair of sets (inf if every arc
            between them is forbidden), zero diagonal; derived.
    """

    weights: np.ndarray
    sets: np.ndarray
    first: int | None = None
    lns_steps: int | None = None
    matrix: np.ndarray = field(init=False, repr=False)
    _vertices: np.ndarray = field(init=False, repr=False)
    _offsets: np.ndarray = field(init=False, repr=False)
    _data: ConfiguredData = field(init=False, repr=False)

    def __post_init__(self) -> None:
        from subtask_opt.tour.configurations import pack_layers

        try:
            raw = np.asarray(self.weights)
            if raw.dtype.kind not in "iuf":
                raise TypeError
            w = np.array(raw, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise InputDataError("GtspProblem.weights must hold real numbers") from None
        if w.ndim != 2 or w.shape[0] != w.shape[1]:
            raise InputDataError(f"GtspProblem.weights must be square, got shape {w.shape}")
        m = w.shape[0]
        if m > MAX_NODES:
            raise InputDataError(f"GtspProblem has {m} vertices; the limit is {MAX_NODES}")
        np.fill_diagonal(w, 0.0)
        bad = np.argwhere(np.isnan(w) | (w < 0) | (np.isfinite(w) & (w > MAX_LEG_TIME)))
        if bad.size:
            u, v = bad[0]
            raise InputDataError(f"GtspProblem.weights from vertex {u} to {v} is {w[u, v]} "
                                 f"(must be in [0, {MAX_LEG_TIME:g}] or inf)")
        s = np.asarray(self.sets)
        if s.shape != (m,) or (s.size and s.dtype.kind not in "iu"):
            raise InputDataError(f"GtspProblem.sets must be {m} whole numbers (the set of "
                                 f"every vertex), got shape {s.shape}")
        s = s.astype(np.int64)
        n = int(s.max()) + 1 if m else 0
        if m and s.min() < 0:
            raise InputDataError(f"GtspProblem.sets must be >= 0, got {int(s.min())}")
        counts = np.bincount(s, minlength=n)
        if n < 3 or np.any(counts == 0):
            missing = np.flatnonzero(counts == 0)
            raise InputDataError(f"GtspProblem.sets must number sets 0..N-1 with N >= 3, each "
                                 f"holding a vertex; got N = {n}"
                                 + (f", set {int(missing[0])} empty" if missing.size else ""))
        w.setflags(write=False)
        s.setflags(write=False)
        object.__setattr__(self, "weights", w)
        object.__setattr__(self, "sets", s)
        vertices = np.argsort(s, kind="stable")  # the vertices grouped by set
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        vertices.setflags(write=False)
        offsets.setflags(write=False)
        object.__setattr__(self, "_vertices", vertices)
        object.__setattr__(self, "_offsets", offsets)
        legs = w[np.ix_(vertices, vertices)]
        data = pack_layers(legs, offsets)
        dist = np.minimum.reduceat(np.minimum.reduceat(legs, offsets[:-1], axis=0),
                                   offsets[:-1], axis=1)
        np.fill_diagonal(dist, 0.0)
        if np.array_equal(data.legs, data.legs.T):
            from subtask_opt.tour.permutation import neighbour_table

            data = data._replace(near=neighbour_table(data.dist, min(NEIGHBOURS, n - 1)))
        steps = LNS_STEPS_PER_SET * n if self.lns_steps is None else self.lns_steps
        require_int("GtspProblem", "lns_steps", steps, 0, 10**9)
        object.__setattr__(self, "lns_steps", int(steps))
        object.__setattr__(self, "_data", data._replace(lns=int(steps)))
        object.__setattr__(self, "matrix", _validated_matrix(dist, allow_inf=np.isinf(dist)))
        _check_first(self.first, n)

    @property
    def vertex_count(self) -> int:
        """Number of vertices M."""
        return int(self.weights.shape[0])

    @property
    def symmetric(self) -> bool:
        """Whether every arc costs the same both ways."""
        return bool(np.array_equal(self.weights, self.weights.T))

    def members(self, k: int) -> np.ndarray:
        """The vertices of set ``k`` (ascending)."""
        return self._vertices[self._offsets[k]:self._offsets[k + 1]]

    def configured_data(self) -> ConfiguredData:
        """The per-vertex costs the clustered GA decodes (vertices grouped by set)."""
        return self._data

    def open_data(self, first: int, last: int) -> ConfiguredData:
        """:meth:`configured_data` with a free return into set ``first`` (from set ``last``
        only, if >= 0): an open path's canonical form."""
        from subtask_opt.tour.configurations import pack_layers

        off = self._offsets
        legs = self.weights[np.ix_(self._vertices, self._vertices)].copy()
        rows = slice(None) if last < 0 else slice(off[last], off[last + 1])
        legs[rows, off[first]:off[first + 1]] = 0.0
        return pack_layers(legs, off)._replace(lns=int(self.lns_steps or 0))

    def decode(self, order: Any, data: ConfiguredData | None = None
               ) -> tuple[float, np.ndarray]:
        """``(cost, vertices)``: the cheapest vertex of every set for the closed tour
        ``order`` of the sets (``vertices[k]`` is visited in set ``order[k]``), by the
        layered shortest path; cost inf if every choice needs a forbidden arc."""
        from subtask_opt.tour import clustered as _gc

        o = _validated_order(order, self.size)
        d = self._data if data is None else data
        within = np.zeros(self.size, dtype=np.int64)
        _gc.decode(o, self.size, d, within)
        vertices = self._vertices[self._offsets[o] + within[o]]
        return self.tour_cost(vertices), vertices

    def tour_cost(self, vertices: Any) -> float:
        """Cost of the closed tour through ``vertices`` (one vertex of every set, in
        visiting order), from the weights; inf if it uses a forbidden arc."""
        v = np.asarray(vertices)
        if (v.shape != (self.size,) or v.dtype.kind not in "iu" or np.any(v < 0)
                or np.any(v >= self.vertex_count)
                or not np.array_equal(np.sort(self.sets[v]), np.arange(self.size))):
            raise ParameterError(f"a tour must visit one vertex of each of the {self.size} "
                                 f"sets, got {vertices!r}")
        v = v.astype(np.int64)
        return float(np.sum(self.weights[v, np.roll(v, -1)]))


NEIGHBOURS = 8
"""Neighbour-list length of a symmetric :class:`GtspProblem`'s local search."""


LNS_STEPS_PER_SET = 1
"""Default large-neighbourhood steps per set of a :class:`GtspProblem` that every restart
individual and child gets (``benchmarks/gtsplib.py --lns``: 0, 1 and 5 per set compared)."""


TourProblem = MatrixProblem | ClusteredProblem | GtspProblem
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

