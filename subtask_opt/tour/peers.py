"""Peer methods for the serial-arm sequencing benchmark, re-implemented from their papers.

Every peer sequences N targets, each with a *layer* of candidate joint
configurations (a (K_i, n) array: the IK solutions of target i), starting and
ending at a home configuration. Every peer returns ``(order, choice)``: ``order``
(N,) the target indices in visiting order and ``choice`` (N,) the row chosen in
each target's layer (indexed by target, not by visit). Leg times come from a
caller-given function ``leg_time(QA (a, n), QB (b, n)) -> (a, b)`` (seconds from
every row of QA to every row of QB), so all peers and our solver can be judged
on one time model.

* :func:`robotsp_method` -- RoboTSP (Suarez-Ruiz, Pham et al., ICRA 2018) as its
  paper describes it: a Euclidean TSP on the hole positions (nearest neighbour,
  then 2-opt), started at the hole nearest the home's tool position, then a
  shortest path through the configuration layers in that order
  (home -> layer of order[0] -> ... -> home) under the metric
  ``max_j |dq_j| / vmax_j``. The configuration graph is layered, so Dijkstra on
  it settles the layers in order; :func:`layered_shortest_path` computes that
  same shortest path as a dynamic programme, O(N K^2).
* :func:`tsp_cspace` -- "TSP in C-space": the highest-manipulability
  configuration per target, then a TSP on the joint-space leg-time matrix
  (nearest neighbour, then 2-opt and Or-opt until neither improves; or LKH by
  ``solver="elkai"``).
* :func:`elkai_gtsp` -- the generalised TSP through the Noon-Bean transformation
  into an asymmetric TSP, solved by LKH (the ``elkai`` package, an optional
  ``bench`` dependency), a stand-in for GLKH.

The local searches (:func:`two_opt`, :func:`or_opt`) are plain NumPy and accept
asymmetric matrices (2-opt reverses a segment; its cost change uses prefix sums
of the forward and backward arc costs along the tour).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    require_in_range,
    require_int,
)

if TYPE_CHECKING:
    from subtask_opt.kinematics.serial import SerialArm

LegTime = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""``leg_time(QA (a, n), QB (b, n)) -> (a, b)`` leg times (s) from each row of QA to each of QB."""

_EPS = 1e-12  # relative improvement below which a local-search move is not taken


# ------------------------------------------------------------------ validation

def _float_array(owner: str, name: str, value: Any, ndim: int) -> np.ndarray:
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"{owner}: {name} must be an array of numbers, "
                             f"got {type(value).__name__}") from None
    if arr.ndim != ndim:
        raise ParameterError(f"{owner}: {name} must be {ndim}-D, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{owner}: {name} must be finite")
    return arr


def _layers(owner: str, layers: Any, home: Any) -> tuple[list[np.ndarray], np.ndarray]:
    """Validated layers (each (K_i, n), K_i >= 1) and home (n,)."""
    h = _float_array(owner, "home", home, 1)
    if h.size == 0:
        raise ParameterError(f"{owner}: home must hold at least one joint value")
    if isinstance(layers, np.ndarray) or not isinstance(layers, Sequence) or len(layers) == 0:
        raise ParameterError(f"{owner}: layers must be a non-empty list of (K_i, n) arrays, "
                             f"got {type(layers).__name__}")
    out = []
    for i, layer in enumerate(layers):
        arr = _float_array(owner, f"layers[{i}]", layer, 2)
        if arr.shape[1] != h.size:
            raise ParameterError(f"{owner}: layers[{i}] has {arr.shape[1]} joint values per "
                                 f"configuration, home has {h.size}")
        if arr.shape[0] == 0:
            raise InputDataError(f"{owner}: target {i} has no configuration (layers[{i}] is "
                                 "empty); drop unreachable targets first")
        out.append(arr)
    return out, h


def _leg_matrix(owner: str, leg_time: LegTime, qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
    """leg_time(qa, qb), checked to be a finite, non-negative (a, b) array."""
    if not callable(leg_time):
        raise ParameterError(f"{owner}: leg_time must be a callable "
                             f"leg_time(QA, QB) -> (a, b), got {leg_time!r}")
    out = np.asarray(leg_time(qa, qb), dtype=np.float64)
    want = (qa.shape[0], qb.shape[0])
    if out.shape != want:
        raise ParameterError(f"{owner}: leg_time returned shape {out.shape} for "
                             f"{qa.shape[0]} x {qb.shape[0]} configurations, expected {want}")
    if not np.all(np.isfinite(out)) or np.any(out < 0):
        raise ParameterError(f"{owner}: leg_time must return finite times >= 0")
    return out


def _square(owner: str, dist: Any) -> np.ndarray:
    d = _float_array(owner, "dist", dist, 2)
    if d.shape[0] != d.shape[1]:
        raise ParameterError(f"{owner}: dist must be square, got shape {d.shape}")
    return d


def _tour(owner: str, tour: Any, n: int) -> np.ndarray:
    t = np.asarray(tour)
    if t.shape != (n,) or not np.issubdtype(t.dtype, np.integer) or \
            not np.array_equal(np.sort(t), np.arange(n)):
        raise ParameterError(f"{owner}: tour must be a permutation of 0..{n - 1}, got {tour!r}")
    return t.astype(np.int64)


# ------------------------------------------------------------------ leg metrics

def max_joint_metric(vmax: Any) -> LegTime:
    """RoboTSP's metric as a leg-time function: ``max_j |qb_j - qa_j| / vmax_j`` (s)."""
    v = _float_array("max_joint_metric", "vmax", vmax, 1)
    if v.size == 0 or np.any(v <= 0):
        raise ParameterError(f"max_joint_metric: vmax must be > 0 for every joint, "
                             f"got {v.tolist()}")

    def metric(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
        diff = np.abs(np.asarray(qb)[None, :, :] - np.asarray(qa)[:, None, :]) / v
        return np.asarray(diff.max(axis=2))

    return metric


def manipulability(arm: SerialArm, q: Any) -> np.ndarray:
    """Yoshikawa's manipulability ``sqrt(det(J J^T))`` of each row of q (K, n) -> (K,).

    J is the 6 x n tool Jacobian; for n < 6 the n x n Gram matrix ``J^T J`` is used.
    """
    qs = _float_array("manipulability", "q", q, 2)
    out = np.empty(qs.shape[0])
    for k, qk in enumerate(qs):
        jac = arm.jacobian(qk)
        gram = jac @ jac.T if jac.shape[1] >= jac.shape[0] else jac.T @ jac
        out[k] = float(np.sqrt(max(np.linalg.det(gram), 0.0)))
    return out


# ------------------------------------------------------------------ tours

def tour_cost(dist: Any, tour: Any) -> float:
    """Cost of the closed tour ``tour[0] -> ... -> tour[-1] -> tour[0]`` under ``dist``."""
    d = _square("tour_cost", dist)
    t = _tour("tour_cost", tour, d.shape[0])
    return float(d[t, np.roll(t, -1)].sum())


def nearest_neighbour_tour(dist: Any, start: int = 0) -> np.ndarray:
    """Greedy tour from ``start``: always on to the nearest unvisited node (ties: lowest index)."""
    d = _square("nearest_neighbour_tour", dist)
    n = d.shape[0]
    require_int("nearest_neighbour_tour", "start", start, 0, max(n - 1, 0))
    seen = np.zeros(n, dtype=bool)
    tour = np.empty(n, dtype=np.int64)
    cur = start
    for k in range(n):
        tour[k] = cur
        seen[cur] = True
        if k < n - 1:
            row = np.where(seen, np.inf, d[cur])
            cur = int(np.argmin(row))
    return tour


def two_opt(dist: Any, tour: Any) -> np.ndarray:
    """2-opt local search on a closed tour until no segment reversal improves it.

    A move (i, j), 0 <= i < j < n, reverses ``tour[i+1 .. j]``; ``tour[0]`` never
    moves. Asymmetric ``dist`` is handled (the reversed segment's arcs change
    direction). Each pass takes, for each i in turn, the best j.
    """
    d = _square("two_opt", dist)
    n = d.shape[0]
    t = _tour("two_opt", tour, n).copy()
    if n < 4 and np.allclose(d, d.T):
        return t
    scale = _EPS * max(float(np.abs(d).max()), 1.0)
    improved = True
    while improved:
        improved = False
        for i in range(n - 2):
            nxt = np.roll(t, -1)
            fwd = np.concatenate([[0.0], np.cumsum(d[t[:-1], t[1:]])])   # fwd[k]: t0..tk
            bwd = np.concatenate([[0.0], np.cumsum(d[t[1:], t[:-1]])])
            j = np.arange(i + 2, n)  # i + 1 == j reverses one node: no change
            a, b = t[i], t[i + 1]
            delta = (d[a, t[j]] + d[b, nxt[j]] - d[a, b] - d[t[j], nxt[j]]
                     + (bwd[j] - bwd[i + 1]) - (fwd[j] - fwd[i + 1]))
            k = int(np.argmin(delta))
            if delta[k] < -scale:
                jj = int(j[k])
                t[i + 1:jj + 1] = t[i + 1:jj + 1][::-1].copy()
                improved = True
    return t


def _or_move(t: np.ndarray, i: int, length: int, p: int, reverse: bool) -> np.ndarray:
    """Tour with ``t[i:i+length]`` moved between ``t[p]`` and its successor (p outside)."""
    seg = t[i:i + length]
    seg = seg[::-1] if reverse else seg
    rest = np.concatenate([t[:i], t[i + length:]])
    q = int(np.nonzero(rest == t[p])[0][0])
    return np.concatenate([rest[:q + 1], seg, rest[q + 1:]])


def or_opt(dist: Any, tour: Any, max_segment: int = 3) -> np.ndarray:
    """Or-opt local search: move a segment of 1..``max_segment`` nodes (kept in order or
    reversed) to another place of the closed tour, until no such move improves it.

    Segments never contain ``tour[0]``, which stays first.
    """
    d = _square("or_opt", dist)
    n = d.shape[0]
    t = _tour("or_opt", tour, n).copy()
    require_int("or_opt", "max_segment", max_segment, 1)
    scale = _EPS * max(float(np.abs(d).max()), 1.0) if n else 0.0
    longest = min(max_segment, n - 2)  # a segment leaves at least two other nodes
    improved = True
    while improved:
        improved = False
        for length in range(1, longest + 1):
            for i in range(1, n - length + 1):
                s0, s1 = t[i], t[i + length - 1]
                prev, nxt = t[i - 1], t[(i + length) % n]
                inner_f = float(d[t[i:i + length - 1], t[i + 1:i + length]].sum())
                inner_b = float(d[t[i + 1:i + length], t[i:i + length - 1]].sum())
                removed = d[prev, s0] + d[s1, nxt] - d[prev, nxt]
                # candidate edges (t[p], t[p+1]) outside the segment and not (prev, s0)
                p = np.array([k for k in range(n) if not (i - 1 <= k <= i + length - 1)])
                if p.size == 0:
                    continue
                a, b = t[p], t[(p + 1) % n]
                keep = d[a, s0] + d[s1, b] - d[a, b] - removed
                flip = d[a, s1] + d[s0, b] - d[a, b] - removed + inner_b - inner_f
                best_keep, best_flip = int(np.argmin(keep)), int(np.argmin(flip))
                if min(keep[best_keep], flip[best_flip]) < -scale:
                    if keep[best_keep] <= flip[best_flip]:
                        t = _or_move(t, i, length, int(p[best_keep]), False)
                    else:
                        t = _or_move(t, i, length, int(p[best_flip]), True)
                    improved = True
                    break
            if improved:
                break
    return t


def local_search(dist: Any, tour: Any) -> np.ndarray:
    """2-opt and Or-opt in turn until neither improves; ``tour[0]`` stays first."""
    t = two_opt(dist, tour)
    while True:
        before = tour_cost(dist, t)
        t = two_opt(dist, or_opt(dist, t))
        if tour_cost(dist, t) >= before - _EPS * max(abs(before), 1.0):
            return t


# ------------------------------------------------------------------ configuration layers

def layered_shortest_path(layers: Sequence[Any], home: Any, order: Any,
                          leg_time: LegTime) -> tuple[np.ndarray, float]:
    """Best configuration per target for a fixed visiting order.

    The shortest path home -> layers[order[0]] -> ... -> layers[order[-1]] -> home
    in the layered graph whose arc costs are ``leg_time``; a dynamic programme over
    the layers (what Dijkstra computes on a layered graph), O(N K^2).

    Returns:
        choice (N,) indexed by target, and the path's cost.
    """
    owner = "layered_shortest_path"
    lay, h = _layers(owner, layers, home)
    n = len(lay)
    o = _tour(owner, order, n)
    hq = h[None, :]
    cost = _leg_matrix(owner, leg_time, hq, lay[o[0]])[0]
    back: list[np.ndarray] = []
    for k in range(1, n):
        step = _leg_matrix(owner, leg_time, lay[o[k - 1]], lay[o[k]])
        total = cost[:, None] + step
        arg = np.argmin(total, axis=0)
        back.append(arg)
        cost = total[arg, np.arange(total.shape[1])]
    cost = cost + _leg_matrix(owner, leg_time, lay[o[-1]], hq)[:, 0]
    last = int(np.argmin(cost))
    best = float(cost[last])
    picked = np.empty(n, dtype=np.int64)
    picked[n - 1] = last
    for k in range(n - 1, 0, -1):
        picked[k - 1] = back[k - 1][picked[k]]
    choice = np.empty(n, dtype=np.int64)
    choice[o] = picked
    return choice, best


def sequence_cost(layers: Sequence[Any], home: Any, order: Any, choice: Any,
                  leg_time: LegTime) -> float:
    """Total leg time of home -> chosen configurations in ``order`` -> home."""
    owner = "sequence_cost"
    lay, h = _layers(owner, layers, home)
    o = _tour(owner, order, len(lay))
    c = np.asarray(choice, dtype=np.int64)
    if c.shape != (len(lay),) or np.any(c < 0) or np.any(
            c >= np.array([layer.shape[0] for layer in lay])):
        raise ParameterError(f"{owner}: choice must hold one valid row index per target, "
                             f"got {choice!r}")
    path = np.vstack([h[None, :]] + [lay[i][c[i]][None, :] for i in o] + [h[None, :]])
    return float(sum(_leg_matrix(owner, leg_time, path[k:k + 1], path[k + 1:k + 2])[0, 0]
                     for k in range(len(path) - 1)))


# ------------------------------------------------------------------ the peers

def robotsp_method(positions: Any, layers: Sequence[Any], home: Any, vmax: Any,
                   leg_time: LegTime | None = None, *,
                   home_position: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """RoboTSP's two-stage method: task-space tour, then configurations along it.

    Args:
        positions: (N, 3) hole positions (m).
        layers: N arrays (K_i, n) of configurations per hole.
        home: (n,) home configuration (rad).
        vmax: (n,) joint speed limits; the configuration metric is
            ``max_j |dq_j| / vmax_j``.
        leg_time: optional true leg-time function; when given, the tour's direction
            (the 2-opt cycle can be run either way from its first hole) is the one
            with the lower true total time after the configuration search. The
            paper leaves the direction open; choosing the better one can only
            favour the peer. None: the nearest-neighbour direction is kept.
        home_position: (3,) where the tool is at home (m); the tour starts at the
            hole nearest it. Default: the mean of ``positions``.

    Returns:
        ``(order, choice)`` as in the module doc.
    """
    owner = "robotsp_method"
    lay, h = _layers(owner, layers, home)
    pos = _float_array(owner, "positions", positions, 2)
    if pos.shape != (len(lay), 3):
        raise ParameterError(f"{owner}: positions must have shape ({len(lay)}, 3) (one row "
                             f"per layer), got {pos.shape}")
    v = _float_array(owner, "vmax", vmax, 1)
    if v.shape != h.shape or np.any(v <= 0):
        raise ParameterError(f"{owner}: vmax must hold {h.size} values > 0, got {v.tolist()}")
    hp = pos.mean(axis=0) if home_position is None else _float_array(
        owner, "home_position", home_position, 1)
    if hp.shape != (3,):
        raise ParameterError(f"{owner}: home_position must have 3 values, got {hp.shape}")
    dist = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=2)
    first = int(np.argmin(np.linalg.norm(pos - hp, axis=1)))
    tour = two_opt(dist, nearest_neighbour_tour(dist, first))
    k = int(np.nonzero(tour == first)[0][0])
    forward = np.roll(tour, -k)
    metric = max_joint_metric(v)
    candidates = [forward]
    if leg_time is not None and len(forward) > 2:
        candidates.append(np.concatenate([forward[:1], forward[1:][::-1]]))
    best: tuple[float, np.ndarray, np.ndarray] | None = None
    for order in candidates:
        choice, _ = layered_shortest_path(lay, h, order, metric)
        score = 0.0 if leg_time is None else sequence_cost(lay, h, order, choice, leg_time)
        if best is None or score < best[0]:
            best = (score, order, choice)
    assert best is not None
    return best[1].astype(np.int64), best[2]


def tsp_cspace(layers: Sequence[Any], home: Any,
               manipulability: Sequence[Any] | Callable[[np.ndarray], np.ndarray],
               leg_time: LegTime, *, solver: str = "local",
               seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """"TSP in C-space": best-manipulability configuration per target, then a joint-space TSP.

    Args:
        layers: N arrays (K_i, n) of configurations per target.
        home: (n,) home configuration; the tour starts and ends there.
        manipulability: N arrays (K_i,) of scores, or a function of a (K, n) layer
            returning (K,) scores (e.g. ``lambda q: manipulability(arm, q)``).
        leg_time: the leg-time function of the TSP's matrix.
        solver: ``"local"`` (nearest neighbour from home, then 2-opt and Or-opt
            until neither improves; NumPy, deterministic) or ``"elkai"`` (LKH on
            the matrix rounded to 1e-5 of its longest leg; needs elkai).
        seed: LKH's seed (``solver="elkai"`` only).

    Returns:
        ``(order, choice)``.
    """
    owner = "tsp_cspace"
    if solver not in ("local", "elkai"):
        raise ParameterError(f"{owner}: solver must be 'local' or 'elkai', got {solver!r}")
    require_int(owner, "seed", seed, 0, 2**31 - 1)
    lay, h = _layers(owner, layers, home)
    choice = np.empty(len(lay), dtype=np.int64)
    for i, layer in enumerate(lay):
        if callable(manipulability):
            score = np.asarray(manipulability(layer), dtype=np.float64)
        else:
            if isinstance(manipulability, np.ndarray) or len(manipulability) != len(lay):
                raise ParameterError(f"{owner}: manipulability must be a callable or one "
                                     f"array per layer ({len(lay)})")
            score = np.asarray(manipulability[i], dtype=np.float64)
        if score.shape != (layer.shape[0],) or not np.all(np.isfinite(score)):
            raise ParameterError(f"{owner}: manipulability of target {i} must be "
                                 f"{layer.shape[0]} finite values, got shape {score.shape}")
        choice[i] = int(np.argmax(score))
    nodes = np.vstack([h[None, :]] + [layer[c][None, :] for layer, c in zip(lay, choice,
                                                                             strict=True)])
    dist = _leg_matrix(owner, leg_time, nodes, nodes)
    if solver == "elkai" and len(lay) >= 2:
        top = float(dist.max())
        mat = np.rint(dist * (1e5 / top if top > 0 else 1.0)).astype(np.int64)
        tour = _lkh_tour(owner, mat, seed=seed, runs=1, max_trials=None, time_limit=None)
    else:
        tour = local_search(dist, nearest_neighbour_tour(dist, 0))
    return tour[1:] - 1, choice


def _lkh_tour(owner: str, mat: np.ndarray, *, seed: int, runs: int, max_trials: int | None,
              time_limit: float | None) -> np.ndarray:
    """LKH's tour (rotated to start at node 0) of an integer matrix with >= 3 nodes."""
    try:
        from elkai import _elkai  # type: ignore[import-untyped]
    except ImportError:
        raise ParameterError(f"{owner} needs the elkai package (pip install "
                             "'subtask_opt[bench]')") from None
    m = mat.shape[0]
    kind = "TSP" if np.array_equal(mat, mat.T) else "ATSP"
    problem = (f"TYPE : {kind}\nDIMENSION : {m}\nEDGE_WEIGHT_TYPE : EXPLICIT\n"
               "EDGE_WEIGHT_FORMAT : FULL_MATRIX\nEDGE_WEIGHT_SECTION\n"
               + "\n".join(" ".join(map(str, row)) for row in mat.tolist()) + "\n")
    params = f"RUNS = {runs}\nSEED = {seed}\nPROBLEM_FILE = :stdin:\n"
    if max_trials is not None:
        params += f"MAX_TRIALS = {max_trials}\n"
    if time_limit is not None:
        params += f"TIME_LIMIT = {time_limit}\n"
    tour = np.asarray(_elkai.solve_problem(params, problem), dtype=np.int64) - 1
    if tour.shape != (m,) or not np.array_equal(np.sort(tour), np.arange(m)):
        raise RuntimeError(f"{owner}: LKH returned no permutation of the {m} nodes")
    return np.roll(tour, -int(np.nonzero(tour == 0)[0][0]))


def noon_bean_matrix(cost: np.ndarray, cluster: np.ndarray, *,
                     resolution: float = 1e4) -> tuple[np.ndarray, np.ndarray, float]:
    """The Noon-Bean transformation of a GTSP into an integer asymmetric TSP matrix.

    Nodes of a cluster are chained in index order into a zero-cost cycle
    (u -> succ(u)); an arc leaving the cluster from u to w costs
    ``round(s * cost[succ(u), w]) + M``, so an optimal ATSP tour visits each
    cluster's nodes consecutively and its entry node w is the GTSP's choice. Other
    arcs inside a cluster are forbidden (larger than any tour).

    Args:
        cost: (m, m) arc costs >= 0 of the GTSP.
        cluster: (m,) cluster id of each node, each cluster's nodes contiguous.
        resolution: the largest arc becomes this many integer units (s).

    Returns:
        (matrix (m, m) int64, succ (m,), s): the ATSP matrix, successors, scale.
    """
    m = cost.shape[0]
    succ = np.arange(m)
    for c in np.unique(cluster):
        idx = np.nonzero(cluster == c)[0]
        succ[idx] = np.roll(idx, -1)
    n_clusters = int(np.unique(cluster).size)
    top = float(cost.max()) if cost.size else 0.0
    s = resolution / top if top > 0 else 1.0
    unit = np.rint(cost * s).astype(np.int64)
    big = int(resolution) * (n_clusters + 1) + 1  # more than any tour's true part
    forbid = 2 * big
    mat = unit[succ, :] + big
    same = cluster[:, None] == cluster[None, :]
    mat[same] = forbid
    mat[np.arange(m), succ] = 0
    np.fill_diagonal(mat, 0)
    return mat, succ, s


def elkai_gtsp(layers: Sequence[Any], home: Any, leg_time: LegTime, *, seed: int = 0,
               runs: int = 1, max_trials: int | None = None, time_limit: float | None = None,
               max_nodes: int = 2500) -> tuple[np.ndarray, np.ndarray]:
    """The GTSP (order and configuration together) by LKH on its Noon-Bean ATSP.

    Clusters: the home (one node) and each target's layer. Arc costs are
    ``leg_time`` between configurations, rounded to 1e-4 of the longest leg. LKH
    runs through the ``elkai`` package with its ``SEED`` set to ``seed`` (same
    seed, same answer).

    Args:
        layers: N arrays (K_i, n); home: (n,); leg_time: the leg-time function.
        seed: LKH's random seed (>= 0).
        runs: LKH's RUNS.
        max_trials: LKH's MAX_TRIALS per run (None: LKH's default, the dimension).
            Measured once on 40 random layers of 8..40 configurations (991 nodes):
            the default took 45 s CPU; ``max_trials=200`` took 7.4 s for a tour 8%
            longer than LKH's with its default trials (and no subgradient ascent).
        time_limit: LKH's TIME_LIMIT (s) over the search, or None.
        max_nodes: refuse larger instances (1 + sum K_i nodes; the dense matrix
            is passed to LKH as text).

    Raises:
        ParameterError: bad inputs, too many nodes, elkai not installed.
    """
    owner = "elkai_gtsp"
    lay, h = _layers(owner, layers, home)
    require_int(owner, "seed", seed, 0, 2**31 - 1)
    require_int(owner, "runs", runs, 1, 10_000)
    require_int(owner, "max_nodes", max_nodes, 2)
    if max_trials is not None:
        require_int(owner, "max_trials", max_trials, 1)
    if time_limit is not None:
        require_in_range(owner, "time_limit", time_limit, 1e-3, 1e7)
    nodes = np.vstack([h[None, :]] + lay)
    cluster = np.concatenate([[0]] + [np.full(layer.shape[0], i + 1)
                                      for i, layer in enumerate(lay)])
    local = np.concatenate([[0]] + [np.arange(layer.shape[0]) for layer in lay])
    m = nodes.shape[0]
    if m > max_nodes:
        raise ParameterError(f"{owner}: {m} nodes (home + configurations) exceed "
                             f"max_nodes={max_nodes}")
    cost = _leg_matrix(owner, leg_time, nodes, nodes)
    if m < 3:  # one target with one configuration: nothing to choose
        return np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64)
    # LKH's ATSP -> TSP transformation needs arcs well below INT_MAX / 2 / PRECISION.
    mat, _, _ = noon_bean_matrix(cost, cluster, resolution=min(1e4, 2e6 / (len(lay) + 2)))
    tour = _lkh_tour(owner, mat, seed=seed, runs=runs, max_trials=max_trials,
                     time_limit=time_limit)
    entries = [int(u) for k, u in enumerate(tour)
               if cluster[u] != cluster[tour[k - 1]] and cluster[u] != 0]
    order = np.array([cluster[u] - 1 for u in entries], dtype=np.int64)
    if len(order) == len(lay) and np.unique(order).size == len(lay):
        choice = np.empty(len(lay), dtype=np.int64)
        choice[order] = local[entries]
        return order, choice
    # Under tight search limits (max_trials, time_limit) LKH may stop before every
    # cluster's zero-cost chain is whole: keep the order of first visits and choose the
    # configurations for it exactly.
    _, first = np.unique(order, return_index=True)
    order = order[np.sort(first)]
    choice, _ = layered_shortest_path(lay, h, order, leg_time)
    return order, choice
