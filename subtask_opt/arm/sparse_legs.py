"""A serial arm's legs for thousands of targets: fewer configurations, candidate legs only.

What :class:`~subtask_opt.arm.serial_problem.SerialProblem` builds instead of its (M, M)
leg matrix when the configurations are many
(:data:`~subtask_opt.arm.serial_problem.SPARSE_FROM`):

1. **Dominated configurations dropped** (exact, :func:`dominated`): the joint model's
   leg time never decreases when one joint's distance grows (it depends on the joint
   distances only through ``max_j d_j / v_j`` and ``max_j d_j / a_j``, both
   non-decreasing). Let [lo_j, hi_j] hold joint j of every configuration of the *other*
   targets and the home (a tour never joins two configurations of one target). A
   configuration q' of a target is dropped when another kept
   configuration q of the same target, a +-2 pi alternative of the same IK solution, is
   joint by joint never farther from any value in [lo_j, hi_j] (equal, or the whole
   interval on q's side of the midpoint of q_j and q'_j): every leg q -> p is then at
   most the leg q' -> p, so a tour through q' is no shorter through q, and an optimal
   tour avoids q'.
2. **Configurations per target bounded** (a stated criterion, tested against the full
   set by the exact GTSP branch and cut on small held-out cases, not a proof,
   :func:`keep_best`): each configuration is scored by the sum, over the target's
   :data:`SCORE_NEIGHBOURS` nearest targets (task space), of its cheapest leg to any of
   that target's configurations (how cheaply the tour can go on in its "family"); a
   target keeps its ``cap`` lowest scores and the configuration with the cheapest leg
   from the home.
3. **Candidate legs** (:func:`build_sparse`): every target's ``k_task`` nearest targets
   in task space and the targets of the ``k_joint`` nearest configurations (in the
   joint metric ``max_j |dq_j| / a_j``) of each of its configurations, made symmetric;
   one (K_a, K_b) block of leg times each, in numba. Never an (M, M) array: memory is
   linear in targets x configurations x candidates (:func:`memory_estimate`).
4. **A bound that stays valid** (:func:`bound_inputs`): the cheapest leg of each of the
   ``k_bound`` nearest pairs in task space, over the configurations of step 1 (so it
   bounds the problem before step 2), and for every other pair the larger of two lower
   bounds: a closed-form one (:func:`cartesian_leg_bound`) at the distance of the
   target's ``k_bound``-th nearest neighbour, and the leg time of the joint-space
   distance from each of its configurations to the nearest configuration of any target
   beyond those (:func:`far_joint_bound`); the input of
   :func:`subtask_opt.tour.sparse.one_tree_bound`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from subtask_opt.base.errors import ParameterError
from subtask_opt.kinematics.joint_moves import JointLimits, _leg_time
from subtask_opt.tour.sparse import SparseLegs

SCORE_NEIGHBOURS = 4
"""Nearest targets (task space) of the score of :func:`keep_best`."""
DEFAULT_CAP = 16
"""Configurations a target keeps by :func:`keep_best` (plus the one nearest the home); in
a cell with obstacles fewer targets keep more (:func:`cap_for`)."""
CONFIGURATION_BUDGET = 10_000
"""Configurations the cap of a cell with obstacles keeps over all targets, where each
target keeps more than :data:`DEFAULT_CAP` (:func:`cap_for`)."""
DEFAULT_K_TASK = 10
"""Candidate targets per target by task-space distance."""
DEFAULT_K_JOINT = 2
"""Nearest configurations (joint space) per configuration whose targets are candidates."""
DEFAULT_K_BOUND = 60
"""Task-space nearest pairs per target whose cheapest leg the bound computes exactly."""
BYTES_PER_CONFIGURATION_PAIR = 8


# ---------------------------------------------------------------- step 1: dominance


@njit(cache=True)
def _dominated(flat, offsets, group, lo, hi):
    """(M,) True where a configuration is dominated (module doc, step 1); ``group`` (M,)
    the IK solution each configuration is an alternative of; ``lo``/``hi`` (N, n) the
    range of each joint over the other targets' configurations and the home."""
    m, n = flat.shape
    out = np.zeros(m, dtype=np.bool_)
    for t in range(offsets.shape[0] - 1):
        for c in range(offsets[t], offsets[t + 1]):
            if out[c]:
                continue
            for d in range(offsets[t], offsets[t + 1]):
                if d == c or out[d] or group[d] != group[c]:
                    continue
                ok = True
                for j in range(n):
                    a = flat[c, j]
                    b = flat[d, j]
                    if a == b:
                        continue
                    mid = 0.5 * (a + b)
                    if (a < b and hi[t, j] > mid) or (a > b and lo[t, j] < mid):
                        ok = False
                        break
                if ok:
                    out[d] = True
    return out


def _others_range(flat: np.ndarray, offsets: np.ndarray,
                  home: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, n) per target the least and greatest value of each joint over every other
    target's configurations and the home (a tour never puts two configurations of one
    target next to each other)."""
    tmin = np.minimum.reduceat(flat, offsets[:-1], axis=0)
    tmax = np.maximum.reduceat(flat, offsets[:-1], axis=0)
    n = tmin.shape[0]
    lo = np.empty_like(tmin)
    hi = np.empty_like(tmax)
    for j in range(flat.shape[1]):
        order = np.argsort(tmin[:, j], kind="stable")
        first, second = order[0], order[1] if n > 1 else order[0]
        lo[:, j] = np.where(np.arange(n) == first, tmin[second, j] if n > 1 else np.inf,
                            tmin[first, j])
        order = np.argsort(-tmax[:, j], kind="stable")
        first, second = order[0], order[1] if n > 1 else order[0]
        hi[:, j] = np.where(np.arange(n) == first, tmax[second, j] if n > 1 else -np.inf,
                            tmax[first, j])
    return np.minimum(lo, home[None]), np.maximum(hi, home[None])


def dominated(flat: np.ndarray, offsets: np.ndarray, group: np.ndarray,
              home: np.ndarray) -> np.ndarray:
    """(M,) mask of the configurations step 1 of the module doc drops (exact)."""
    lo, hi = _others_range(flat, offsets, home)
    return _dominated(np.ascontiguousarray(flat), offsets, np.ascontiguousarray(group), lo,
                      hi)  # type: ignore[no-any-return]


# ---------------------------------------------------------------- step 2: the cap


@njit(cache=True)
def _scores(flat, offsets, near, limits):
    inv_v = 1.0 / limits.velocity
    inv_a = 1.0 / limits.acceleration
    inv_j = 1.0 / limits.jerk
    out = np.zeros(flat.shape[0])
    for t in range(offsets.shape[0] - 1):
        for c in range(offsets[t], offsets[t + 1]):
            s = 0.0
            for k in range(near.shape[1]):
                b = near[t, k]
                best = np.inf
                for d in range(offsets[b], offsets[b + 1]):
                    v = _leg_time(flat, c, flat, d, inv_v, inv_a, inv_j)
                    if v < best:
                        best = v
                s += best
            out[c] = s
    return out


def keep_best(flat: np.ndarray, offsets: np.ndarray, points: np.ndarray, home_legs: np.ndarray,
              limits: JointLimits, cap: int) -> np.ndarray:
    """(M,) mask of the configurations step 2 of the module doc keeps."""
    n = offsets.shape[0] - 1
    counts = np.diff(offsets)
    keep = np.ones(flat.shape[0], dtype=bool)
    if counts.max() <= cap or n < 2:
        return keep
    near = nearest_targets(points, min(SCORE_NEIGHBOURS, n - 1))
    score = _scores(np.ascontiguousarray(flat), offsets, near, limits)
    keep[:] = False
    for t in range(n):
        lo, hi = offsets[t], offsets[t + 1]
        rank = np.argsort(score[lo:hi], kind="stable")[:cap]
        keep[lo + rank] = True
        keep[lo + int(np.argmin(home_legs[lo:hi]))] = True
    return keep


def cap_for(targets: int, obstacles: bool) -> int:
    """Configurations each of ``targets`` targets keeps: :data:`DEFAULT_CAP`; among
    ``obstacles``, more while all of them stay within :data:`CONFIGURATION_BUDGET`. The
    score of :func:`keep_best` cannot see that a leg passes through an obstacle: on
    RoboTSP's 245 holes in their cell, 16 of the 40 configurations a hole has made the
    tour 13% longer than 40 (legs in collision forbidden), while on an open 500-hole panel
    20 made it 0.06-0.3% longer than 16 (four seeds: more configurations, same kicks)."""
    if not obstacles:
        return DEFAULT_CAP
    return max(DEFAULT_CAP, CONFIGURATION_BUDGET // max(targets, 1))


def nearest_targets(points: np.ndarray, k: int) -> np.ndarray:
    """(N, k) the k nearest other targets of each (task space, nearest first)."""
    from scipy.spatial import cKDTree

    n = points.shape[0]
    k = min(k, n - 1)
    if k <= 0:
        return np.zeros((n, 0), dtype=np.int64)
    _, idx = cKDTree(points).query(points, k=k + 1)
    idx = np.asarray(idx, dtype=np.int64).reshape(n, k + 1)
    out = np.empty((n, k), dtype=np.int64)
    for i in range(n):  # drop the target itself (first, unless duplicates tie)
        row = idx[i][idx[i] != i][:k]
        out[i] = row
    return out


# ---------------------------------------------------------------- step 3: candidate legs


@njit(cache=True)
def _blocks(flat, offsets, nbr, start, total, limits):
    inv_v = 1.0 / limits.velocity
    inv_a = 1.0 / limits.acceleration
    inv_j = 1.0 / limits.jerk
    legs = np.empty(total)
    for a in range(nbr.shape[0]):
        for s in range(nbr.shape[1]):
            b = nbr[a, s]
            if b < 0:
                continue
            p = start[a, s]
            for r in range(offsets[a], offsets[a + 1]):
                for c in range(offsets[b], offsets[b + 1]):
                    legs[p] = _leg_time(flat, r, flat, c, inv_v, inv_a, inv_j)
                    p += 1
    return legs


def _joint_candidates(flat: np.ndarray, offsets: np.ndarray, limits: JointLimits,
                      k: int) -> list[tuple[int, int]]:
    """Target pairs of each configuration's k nearest configurations of other targets
    (metric max_j |dq_j| / a_j)."""
    from scipy.spatial import cKDTree

    if k <= 0:
        return []
    owner = np.repeat(np.arange(offsets.shape[0] - 1), np.diff(offsets))
    scaled = flat / limits.acceleration
    kk = min(k + int(np.diff(offsets).max()), flat.shape[0])
    _, idx = cKDTree(scaled).query(scaled, k=kk, p=np.inf)
    idx = np.asarray(idx).reshape(flat.shape[0], kk)
    pairs = set()
    other = owner[idx] != owner[:, None]
    for r in range(flat.shape[0]):
        row = idx[r][other[r]][:k]
        for c in row:
            pairs.add((int(owner[r]), int(owner[c])))
    return list(pairs)


def build_sparse(flat: np.ndarray, offsets: np.ndarray, points: np.ndarray,
                 home_legs: np.ndarray, limits: JointLimits, *, k_task: int = DEFAULT_K_TASK,
                 k_joint: int = DEFAULT_K_JOINT, extra: list[tuple[int, int]] | None = None,
                 penalty: float) -> SparseLegs:
    """The :class:`~subtask_opt.tour.sparse.SparseLegs` of step 3 (module doc); ``extra``
    adds pairs (the legs a search asked for)."""
    n = offsets.shape[0] - 1
    near = nearest_targets(points, k_task)
    pairs = {(a, int(b)) for a in range(n) for b in near[a]}
    pairs.update(_joint_candidates(flat, offsets, limits, k_joint))
    pairs.update(extra or [])
    pairs |= {(b, a) for a, b in pairs}
    pairs = {p for p in pairs if p[0] != p[1]}
    lists: list[list[int]] = [[] for _ in range(n)]
    for a, b in sorted(pairs):
        lists[a].append(b)
    width = max(1, max(len(x) for x in lists))
    nbr = np.full((n, width), -1, dtype=np.int64)
    start = np.full((n, width), -1, dtype=np.int64)
    counts = np.diff(offsets)
    p = 0
    for a in range(n):
        for s, b in enumerate(lists[a]):
            nbr[a, s] = b
            start[a, s] = p
            p += int(counts[a] * counts[b])
    legs = _blocks(np.ascontiguousarray(flat), offsets, nbr, start, p, limits)
    return SparseLegs(offsets, nbr, start, legs, np.ascontiguousarray(home_legs),
                      np.ascontiguousarray(points, dtype=np.float64), float(penalty))


def memory_estimate(configurations: int, targets: int, *, k_task: int = DEFAULT_K_TASK,
                    k_joint: int = DEFAULT_K_JOINT, cap: int = DEFAULT_CAP) -> int:
    """Bytes the candidate legs of a problem may hold (before they are built): every
    target's candidates (about 2 (k_task + k_joint), symmetric) times its kept
    configurations squared, 8 bytes a leg, plus the configurations themselves."""
    kept = min(configurations / max(targets, 1), cap + 1)
    per_pair = kept * kept * BYTES_PER_CONFIGURATION_PAIR
    return int(targets * 2 * (k_task + k_joint) * per_pair + configurations * 6 * 8 * 4)


# ---------------------------------------------------------------- step 4: the bound


def reach_levers(arm: Any) -> np.ndarray | None:
    """(n,) for each joint an upper bound on the tool point's distance from its axis in
    any configuration: the lengths of the rigid links from the joint to the tool point,
    summed (Pinocchio's joint placements at q = 0). None when a joint is not revolute
    (a prismatic joint changes those lengths)."""
    import pinocchio as pin

    if not bool(np.all(arm.revolute)):
        return None
    model = arm.model
    data = model.createData()
    pin.forwardKinematics(model, data, np.zeros(model.nq))
    pin.updateFramePlacements(model, data)
    points = [np.array(data.oMi[j].translation) for j in range(1, model.njoints)]
    points.append(np.array(data.oMf[arm.tool_frame_id].translation))
    seg = np.linalg.norm(np.diff(np.array(points), axis=0), axis=1)
    return np.cumsum(seg[::-1])[::-1].copy()


def cartesian_leg_bound(distance: np.ndarray, levers: np.ndarray,
                        limits: JointLimits) -> np.ndarray:
    """A lower bound on the joint model's time of any leg whose tool point moves
    ``distance`` (m) in a straight line: the tool point's path along the joint-space
    line is at most ``sum_j L_j d_j`` long (its speed is at most sum_j L_j |qd_j|), so
    ``max_j d_j / v_j >= D / sum_j L_j v_j`` and likewise for the accelerations; the time
    grows with both (phase-synchronised trapezoid; a jerk limit only lengthens it)."""
    d = np.maximum(np.asarray(distance, dtype=np.float64), 0.0)
    tv = d / float(np.sum(levers * limits.velocity))
    ta = d / float(np.sum(levers * limits.acceleration))
    tri = 2.0 * np.sqrt(ta)
    trap = tv + ta / np.maximum(tv, 1e-300)
    return np.where(ta >= tv * tv, tri, trap)  # type: ignore[no-any-return]


@njit(cache=True)
def _pair_minima(flat, offsets, ea, eb, limits):
    inv_v = 1.0 / limits.velocity
    inv_a = 1.0 / limits.acceleration
    inv_j = 1.0 / limits.jerk
    out = np.empty(ea.shape[0])
    for e in range(ea.shape[0]):
        a = ea[e]
        b = eb[e]
        best = np.inf
        for r in range(offsets[a], offsets[a + 1]):
            for c in range(offsets[b], offsets[b + 1]):
                v = _leg_time(flat, r, flat, c, inv_v, inv_a, inv_j)
                if v < best:
                    best = v
        out[e] = best
    return out


@njit(cache=True)
def _far_scaled(dist, idx, owner, offsets, near):
    """(N,) per target a the least Chebyshev distance (the query's metric) from one of
    its configurations to a configuration of a target neither a nor among ``near[a]``:
    the first such among each configuration's queried neighbours ``idx`` (nearest
    first), or the last queried distance when all are a's or its near targets' (every
    configuration not returned is at least that far); +inf when the query returned every
    configuration and none qualifies."""
    n = offsets.shape[0] - 1
    m, k = idx.shape
    mark = np.zeros(n, dtype=np.bool_)
    out = np.full(n, np.inf)
    for a in range(n):
        mark[a] = True
        for s in range(near.shape[1]):
            mark[near[a, s]] = True
        for r in range(offsets[a], offsets[a + 1]):
            d = np.inf if k >= m else dist[r, k - 1]
            for s in range(k):
                if not mark[owner[idx[r, s]]]:
                    d = dist[r, s]
                    break
            if d < out[a]:
                out[a] = d
        mark[a] = False
        for s in range(near.shape[1]):
            mark[near[a, s]] = False
    return out


@njit(cache=True)
def _single_joint_times(ta, limits):
    """(N,) the least leg time over joints j of a move of joint j alone by
    ``ta[i] * acceleration[j]`` (so that its ``d_j / a_j`` is ``ta[i]``)."""
    inv_v = 1.0 / limits.velocity
    inv_a = 1.0 / limits.acceleration
    inv_j = 1.0 / limits.jerk
    nj = inv_v.shape[0]
    q = np.zeros((2, nj))
    out = np.empty(ta.shape[0])
    for i in range(ta.shape[0]):
        best = np.inf
        if np.isfinite(ta[i]):
            for j in range(nj):
                q[1, :] = 0.0
                q[1, j] = ta[i] * limits.acceleration[j]
                v = _leg_time(q, 0, q, 1, inv_v, inv_a, inv_j)
                if v < best:
                    best = v
        out[i] = best
    return out


FAR_QUERY = 16
"""Nearest configurations (joint space) :func:`far_joint_bound` queries per configuration."""


def far_joint_bound(flat: np.ndarray, offsets: np.ndarray, near: np.ndarray,
                    limits: JointLimits, *, query: int = FAR_QUERY) -> np.ndarray:
    """(N,) for each target a a lower bound on every leg between a configuration of a
    and one of a target neither a nor in ``near[a]`` (N, k).

    Why it is valid: the leg time depends on the joint distances d_j only through
    quantities that never decrease when one d_j grows (module doc, step 1), so a leg is
    at least the time of moving its joint j alone by d_j, for each j. Let ``D`` be the
    least Chebyshev distance ``max_j d_j / a_j`` (``a`` the accelerations) between a's
    configurations and those of the far targets (:func:`_far_scaled`, a k-d tree
    query; a lower bound of it when none of the ``query`` nearest is far): every such
    leg has a joint with ``d_j >= D a_j``, so it takes at least
    ``min_j time(joint j alone by D a_j)``. ``D`` is shrunk by a relative 1e-9 for the
    rounding of the scaled coordinates."""
    from scipy.spatial import cKDTree

    n = offsets.shape[0] - 1
    m = flat.shape[0]
    if n < 2 or m == 0:
        return np.full(n, np.inf)
    owner = np.repeat(np.arange(n, dtype=np.int64), np.diff(offsets))
    scaled = np.ascontiguousarray(flat / limits.acceleration)
    k = min(int(query), m)
    dist, idx = cKDTree(scaled).query(scaled, k=k, p=np.inf)
    dist = np.asarray(dist, dtype=np.float64).reshape(m, k)
    idx = np.asarray(idx, dtype=np.int64).reshape(m, k)
    far = _far_scaled(dist, idx, owner, offsets,
                      np.ascontiguousarray(near, dtype=np.int64).reshape(n, -1))
    far = np.maximum(far * (1.0 - 1e-9) - 1e-15, 0.0)
    return _single_joint_times(far, limits)  # type: ignore[no-any-return]


def bound_inputs(flat: np.ndarray, offsets: np.ndarray, points: np.ndarray,
                 home_legs: np.ndarray, limits: JointLimits, levers: np.ndarray | None, *,
                 k_bound: int = DEFAULT_K_BOUND, slack: float = 1e-5,
                 far_query: int = FAR_QUERY,
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(edges, weights, rho, home) for :func:`~subtask_opt.tour.sparse.one_tree_bound`
    (step 4 of the module doc) over the configurations ``flat``; ``slack`` (m) how far a
    configuration's tool point may be from its target's (the IK's tolerance, twice);
    ``far_query`` the joint-space neighbours :func:`far_joint_bound` queries (0: the
    closed-form bound alone)."""
    n = offsets.shape[0] - 1
    k = min(k_bound, n - 1)
    home = np.minimum.reduceat(home_legs, offsets[:-1])
    if k <= 0:
        return np.zeros((0, 2), np.int64), np.zeros(0), np.zeros(n), home
    from scipy.spatial import cKDTree

    dist, idx = cKDTree(points).query(points, k=k + 1)
    idx = np.asarray(idx, dtype=np.int64).reshape(n, k + 1)
    a = np.repeat(np.arange(n), k + 1)
    b = idx.ravel()
    edges = np.unique(np.sort(np.stack([a, b], axis=1)[a != b], axis=1), axis=0)
    weights = _pair_minima(np.ascontiguousarray(flat), offsets, edges[:, 0].copy(),
                           edges[:, 1].copy(), limits)
    if k == n - 1:  # every pair is an edge: no other pair to bound
        return edges, weights, np.full(n, np.inf), home
    rho = np.zeros(n)
    if levers is not None:  # every target beyond a's k nearest is at least this far from it
        far = np.asarray(dist, dtype=np.float64).reshape(n, k + 1)[:, k]
        rho = cartesian_leg_bound(far - 2 * slack, levers, limits)
    if far_query > 0:  # a non-edge (a, b) has b beyond a's k nearest (and a beyond b's)
        near = np.stack([row[row != i][:k] for i, row in enumerate(idx)])
        rho = np.maximum(rho, far_joint_bound(flat, offsets, near, limits, query=far_query))
    return edges, weights, rho, home


def check_memory(needed: int, *, limit: int | None = None) -> None:
    """Refuse a problem whose legs would not fit in memory, before any work: ``needed``
    bytes against ``limit`` (default: the machine's available memory, /proc/meminfo)."""
    if limit is None:
        limit = available_memory()
    if limit is not None and needed > limit:
        raise ParameterError(f"the legs of this problem need about {needed / 2**30:.2f} GiB, "
                             f"more than the {limit / 2**30:.2f} GiB of memory available: use "
                             "a coarser axis step or fewer targets")


def available_memory() -> int | None:
    """MemAvailable of /proc/meminfo in bytes (None where it cannot be read)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError):
        return None
    return None


__all__ = ["CONFIGURATION_BUDGET", "DEFAULT_CAP", "DEFAULT_K_BOUND", "DEFAULT_K_JOINT",
           "DEFAULT_K_TASK", "FAR_QUERY", "available_memory", "bound_inputs", "build_sparse",
           "cap_for", "cartesian_leg_bound", "check_memory", "dominated", "far_joint_bound",
           "keep_best", "memory_estimate", "nearest_targets", "reach_levers"]
