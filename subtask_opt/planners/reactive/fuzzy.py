"""Reactive navigation by fuzzy via-point selection (SPEC §3, seed paper 001).

At each sampling time the robot considers the via-points it can reach in one
period with a grid of heading changes x speeds, predicts the sonar scan at each
(:func:`.sonar.predict_scan`), grades each against three fuzzy goals and moves
to the candidate of largest decision membership:

* G1, clearance: ``muG1 = 1 / (1 + exp(-d1 (U_min - C1)))`` (eq. 4; 1 for every
  candidate when no candidate sees anything);
* G2, small repulsive potential ``F_r = sum_k (R_max - U_k)`` (eq. 3, 5);
* G3, closeness to the target: ``muG3 = 0.9 - 0.8 (D - D_min) / (D_max - D_min)`` (eq. 6);
* decision ``muD = min(muG1, muG2, muG3)`` (eq. 7), the best candidate is the
  argmax (the paper's Table 1: candidate 4, ``muD = 0.4``).

Eq. 1 weighs the goals, ``D = G1^w1 ∩ ... ∩ Gm^wm``: a goal of importance
``w_j`` enters the intersection with membership ``muGj ** w_j`` (Yager's
weighting), so a more important goal (``w_j > 1``) is harder to satisfy and
dominates the minimum. The paper names Saaty's eigenvector method for the
weights (:func:`saaty_weights`) but runs the plain minimum; so do we by
default (``FuzzyParams.weights = (1, 1, 1)``).

Eq. 5 as printed, ``1 / (1 + d2 / (F_r + d3))``, *increases* with ``F_r``,
which contradicts its own goal (``F_r < C2``) and its special case (1 when
``F_r = 0``); we use the reciprocal ratio, ``muG2 = 1 / (1 + (F_r + d3) / d2)``,
which falls from ``d2 / (d2 + d3)`` at ``F_r = 0`` to 1/2 at ``F_r = d2 - d3``.

Local minimum (paper §4, after Borenstein): when the heading points more than
90 degrees away from the target, the robot follows the wall by aiming at a
virtual target a short distance away at 90 degrees from the direction of the
nearest echo, until the condition clears. The paper leaves the details open;
here they are (all in :class:`FuzzyParams`):

* *when*: the heading test holds, an echo is nearer than the goal, and the
  goal distance has not reached a new low for ``trap_steps`` decisions (a
  robot merely swerving round an obstacle is not trapped);
* *which side*: the one whose wall tangent is closer to the current heading,
  kept for the whole episode; the followed wall is the nearest echo on that
  side (or within ``wall_front_angle`` past straight ahead), so walls met
  head-on turn the robot away and a wall lost from view turns it back toward
  that side (rounding convex corners);
* *where*: the paper's target, shifted across so the robot tracks
  ``follow_distance`` from the wall;
* *until*: the heading is back within 90 degrees of the goal (or no echo is
  nearer than the goal) *and*, with ``leave_closer``, the robot is closer to
  the goal than where the episode began (the Bug-2 rule that keeps it from
  falling back into the same trap). An episode that lasts ``max_follow_steps``
  is abandoned and the next one follows the other side.

An admissibility filter (not in the paper) drops candidates whose path comes
closer than ``radius + safety_margin`` to a predicted wall. The speed grid
includes 0 (turning in place); those candidates are used only when no moving
candidate is admissible, so the robot never drives into what it has seen.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    require_in_range,
    require_int,
    require_non_negative,
    require_positive,
)
from subtask_opt.base.geometry import wrap_angle
from subtask_opt.planners.reactive.sonar import SonarRing, predict_scan
from subtask_opt.planners.reactive.unicycle import MAX_GRID, Unicycle, integrate_arc

MAX_WEIGHT = 100.0
"""Largest importance weight of a fuzzy goal."""


@dataclass(frozen=True)
class FuzzyParams:
    """Parameters of the fuzzy via-point navigator.

    Attributes:
        c1: clearance ``C1`` at which muG1 = 1/2 (distance from the robot centre).
        d1: slope ``d1`` of the muG1 sigmoid (per unit distance, > 0).
        d2: scale ``d2`` of muG2 (units of ``F_r``, > 0).
        d3: offset ``d3`` of muG2 (>= 0).
        n_headings: heading changes per step (>= 1), spread over the turn-rate limit.
        n_speeds: speeds per step (>= 1), spread over ``[0, max_speed]``.
        escape: use the local-minimum test and wall following.
        virtual_target_distance: distance from the robot to the virtual target (> 0).
        leave_closer: end a wall-following episode only once the robot is
            closer to the target than where the episode began.
        safety_margin: extra clearance beyond the body radius required of a
            moving candidate's predicted path (>= 0).
        wall_front_angle: the followed wall is the nearest echo on the wall's
            side or within this angle (rad) past straight ahead.
        trap_steps: decisions without a new lowest goal distance before the
            heading test may start an episode (>= 0).
        follow_distance: distance kept from the followed wall (> 0); echoes
            beyond twice this distance count as "wall lost".
        max_follow_steps: decisions after which an episode is abandoned (>= 1).
        weights: importance ``(w1, w2, w3)`` of G1, G2, G3 in eq. 1, each in
            ``(0, MAX_WEIGHT]``; ``(1, 1, 1)`` is the paper's plain minimum
            (see :func:`saaty_weights` for weights from pairwise comparisons).
    """

    c1: float = 0.6
    d1: float = 10.0
    d2: float = 30.0
    d3: float = 0.0
    n_headings: int = 9
    n_speeds: int = 4
    escape: bool = True
    virtual_target_distance: float = 1.0
    leave_closer: bool = True
    safety_margin: float = 0.08
    wall_front_angle: float = math.radians(10.0)
    trap_steps: int = 10
    follow_distance: float = 0.8
    max_follow_steps: int = 80
    weights: tuple[float, float, float] = (1.0, 1.0, 1.0)

    def __post_init__(self) -> None:
        require_positive("FuzzyParams", "c1", self.c1)
        require_positive("FuzzyParams", "d1", self.d1)
        require_positive("FuzzyParams", "d2", self.d2)
        require_non_negative("FuzzyParams", "d3", self.d3)
        require_int("FuzzyParams", "n_headings", self.n_headings, 1, MAX_GRID)
        require_int("FuzzyParams", "n_speeds", self.n_speeds, 1, MAX_GRID)
        require_positive("FuzzyParams", "virtual_target_distance", self.virtual_target_distance)
        require_non_negative("FuzzyParams", "safety_margin", self.safety_margin)
        require_in_range("FuzzyParams", "wall_front_angle", self.wall_front_angle, 0.0, math.pi)
        require_int("FuzzyParams", "trap_steps", self.trap_steps, 0)
        require_positive("FuzzyParams", "follow_distance", self.follow_distance)
        require_int("FuzzyParams", "max_follow_steps", self.max_follow_steps, 1)
        object.__setattr__(self, "weights", check_weights("FuzzyParams.weights", self.weights,
                                                          goals=3))


def check_weights(owner: str, weights: Any, *, goals: int) -> tuple[float, ...]:
    """``weights`` as a tuple of ``goals`` floats in ``(0, MAX_WEIGHT]``, or a ParameterError."""
    try:
        w = tuple(weights)
    except TypeError:
        raise ParameterError(f"{owner} must be {goals} numbers, got {weights!r}") from None
    if len(w) != goals:
        raise ParameterError(f"{owner} must be {goals} numbers, got {weights!r}")
    out = []
    for j, wj in enumerate(w):
        ok = not isinstance(wj, bool) and isinstance(wj, (int, float, np.integer, np.floating))
        if not ok or not 0.0 < float(wj) <= MAX_WEIGHT:
            raise ParameterError(f"{owner}[{j}] must be a number in (0, {MAX_WEIGHT:g}], "
                                 f"got {wj!r}")
        out.append(float(wj))
    return tuple(out)


def saaty_weights(pairwise: Any) -> tuple[np.ndarray, float]:
    """Importance weights from a pairwise-comparison matrix (Saaty's eigenvector method).

    ``pairwise[i][j]`` says how much more important goal i is than goal j
    (positive, reciprocal: ``a_ji = 1 / a_ij``, ones on the diagonal). The
    weights are the principal (Perron) eigenvector, scaled so that they sum to
    the number of goals m (Yager: equal importance gives all ones, the plain
    minimum). For a consistent matrix, ``a_ij = v_i / v_j``, this is
    ``m v / sum(v)`` exactly.

    Returns:
        ``(weights, consistency_index)`` with ``CI = (lambda_max - m) / (m - 1)``
        (0 for a consistent matrix; 0 when m = 1).

    Raises:
        InputDataError: not a square, positive, reciprocal matrix of finite numbers.
    """
    try:
        a = np.asarray(pairwise, dtype=float)
    except (TypeError, ValueError):
        raise InputDataError(f"pairwise comparisons must be a square matrix of numbers, "
                             f"got {pairwise!r}") from None
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] == 0:
        raise InputDataError(f"pairwise comparisons must be a square (m, m) matrix, got shape "
                             f"{a.shape}")
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise InputDataError("pairwise comparisons must be finite and > 0")
    if not np.allclose(a * a.T, 1.0, rtol=1e-9, atol=0.0):
        raise InputDataError("pairwise comparisons must be reciprocal: a[j][i] = 1 / a[i][j] "
                             "(and 1 on the diagonal)")
    m = a.shape[0]
    vals, vecs = np.linalg.eig(a)
    k = int(np.argmax(vals.real))
    v = np.abs(vecs[:, k].real)
    weights = m * v / v.sum()
    ci = float((vals[k].real - m) / (m - 1)) if m > 1 else 0.0
    return weights, max(ci, 0.0)


# ---------------------------------------------------------------- memberships (eq. 3-7)

def repulsive_potential(scans: np.ndarray, max_range: float) -> np.ndarray:
    """``F_r = sum_k (R_max - U_k)`` (eq. 3) of each row of ``scans`` (c, n)."""
    return np.sum(max_range - np.atleast_2d(scans), axis=1)


def mu_clearance(u_min: np.ndarray, c1: float, d1: float, max_range: float) -> np.ndarray:
    """muG1 (eq. 4): sigmoid in the nearest reading; all ones when no candidate sees anything."""
    u_min = np.asarray(u_min, dtype=float)
    if np.all(u_min >= max_range):
        return np.ones_like(u_min)
    return 1.0 / (1.0 + np.exp(-d1 * (u_min - c1)))


def mu_repulsion(f_r: np.ndarray, d2: float, d3: float) -> np.ndarray:
    """muG2 (eq. 5, ratio inverted, see the module docstring); all ones when every F_r is 0."""
    f_r = np.asarray(f_r, dtype=float)
    if np.all(f_r <= 0.0):
        return np.ones_like(f_r)
    return 1.0 / (1.0 + (f_r + d3) / d2)


def mu_target(dist: np.ndarray) -> np.ndarray:
    """muG3 (eq. 6): 0.9 for the candidate nearest the target down to 0.1 for the farthest."""
    dist = np.asarray(dist, dtype=float)
    lo, hi = float(np.min(dist)), float(np.max(dist))
    if hi - lo <= 1e-12 * max(1.0, hi):
        return np.full_like(dist, 0.9)
    return 0.9 - 0.8 * (dist - lo) / (hi - lo)


def fuzzy_decision(memberships: np.ndarray, admissible: np.ndarray | None = None,
                   weights: Any = None) -> tuple[int, np.ndarray]:
    """Bellman-Zadeh decision (eq. 1, 7): ``muD = min_j muGj ** w_j``, best = argmax muD.

    Args:
        memberships: (c, m) membership of each of c candidates in m fuzzy goals.
        admissible: optional (c,) mask; inadmissible candidates cannot be chosen.
        weights: optional (m,) importance of the goals (each in ``(0, MAX_WEIGHT]``);
            None or all ones is the plain minimum of eq. 7.

    Returns:
        ``(index, mu_d)``: 0-based index of the chosen candidate (the first on
        ties) and the (c,) decision memberships.
    """
    mu = np.asarray(memberships, dtype=float)
    if mu.ndim != 2 or mu.shape[0] == 0 or mu.shape[1] == 0:
        raise InputDataError(f"memberships must be a non-empty (c, m) array, got {mu.shape}")
    if not np.all(np.isfinite(mu)) or mu.min() < 0.0 or mu.max() > 1.0:
        raise InputDataError("memberships must be finite and in [0, 1]")
    if weights is not None:
        w = np.array(check_weights("fuzzy_decision.weights", weights, goals=mu.shape[1]))
        if np.any(w != 1.0):
            mu = mu ** w[None, :]
    mu_d = mu.min(axis=1)
    score = mu_d if admissible is None else np.where(admissible, mu_d, -1.0)
    return int(np.argmax(score)), mu_d


# ---------------------------------------------------------------- navigator

@dataclass(frozen=True)
class NavDecision:
    """One step of a navigator: the command and why.

    Attributes:
        v, omega: forward speed and turn rate to hold for one sampling period.
        mu: (4,) muG1, muG2, muG3 (unweighted) and muD of the chosen candidate
            (NaN for the baselines).
        escaping: whether the robot is wall-following out of a local minimum.
        target: the point steered to (the goal, or the virtual target).
    """

    v: float
    omega: float
    mu: np.ndarray = field(default_factory=lambda: np.full(4, np.nan))
    escaping: bool = False
    target: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))


class FuzzyNavigator:
    """Fuzzy via-point selection with optional local-minimum escape.

    Stateful (the wall-following episode); call :meth:`reset` before a new run.
    Not for sharing between threads: one navigator per run (:func:`.simulation.simulate`
    builds a fresh one per call when given a name); the robot and sonar it holds are
    immutable and may be shared.
    """

    def __init__(self, robot: Unicycle, sonar: SonarRing,
                 params: FuzzyParams | None = None) -> None:
        self.robot = robot
        self.sonar = sonar
        self.params = params or FuzzyParams()
        self.name = "fuzzy" if self.params.escape else "fuzzy-no-escape"
        self._v, self._omega = robot.commands(self.params.n_headings, self.params.n_speeds)
        self.reset()

    def reset(self) -> None:
        """Forget any wall-following episode."""
        self._side = 0           # +1: virtual target CCW of the nearest echo, -1: CW, 0: off
        self._entry_dist = math.inf
        self._best_dist = math.inf
        self._since_best = 0     # decisions since the goal distance last hit a new low
        self._episode_steps = 0
        self._last_side = 0      # side of the last episode that timed out (0: none)

    def candidates(self, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Via-point candidates (c, 3) of ``pose`` and the midpoints (c, 2) of their arcs."""
        cand = integrate_arc(pose, self._v, self._omega, self.robot.dt)
        mid = integrate_arc(pose, self._v, self._omega, 0.5 * self.robot.dt)[:, :2]
        return cand, mid

    def evaluate(self, pose: np.ndarray, ranges: np.ndarray,
                 target: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Memberships (c, 3), admissibility (c,) and candidate poses (c, 3) toward ``target``."""
        p = self.params
        r_max = self.sonar.max_range
        cand, mid = self.candidates(pose)
        pred, clearance = predict_scan(self.sonar, ranges, pose, cand, mid)
        dist = np.hypot(cand[:, 0] - target[0], cand[:, 1] - target[1])
        mu = np.column_stack([
            mu_clearance(pred.min(axis=1), p.c1, p.d1, r_max),
            mu_repulsion(repulsive_potential(pred, r_max), p.d2, p.d3),
            mu_target(dist),
        ])
        moving = self._v > 0.0
        admissible = moving & (clearance >= self.robot.radius + p.safety_margin)
        if not np.any(admissible):  # boxed in: turn in place
            admissible = ~moving
        return mu, admissible, cand

    def _trapped(self, pose: np.ndarray, ranges: np.ndarray,
                 goal: np.ndarray) -> tuple[bool, bool, float]:
        """``(trapped, blocked, dist)``: the local-minimum test (heading more than 90 degrees
        off the goal while an echo is nearer than the goal), whether an echo is nearer
        than the goal, and the distance to the goal."""
        dist = math.hypot(goal[0] - pose[0], goal[1] - pose[1])
        off = abs(float(wrap_angle(pose[2] - math.atan2(goal[1] - pose[1], goal[0] - pose[0]))))
        blocked = float(np.min(ranges)) < min(dist, self.sonar.max_range)
        return off > 0.5 * math.pi and blocked, blocked, dist

    def _virtual_target(self, pose: np.ndarray, ranges: np.ndarray) -> np.ndarray:
        """The virtual target of wall following.

        ``virtual_target_distance`` ahead along the followed wall's tangent (90 degrees
        from the direction of its nearest echo), shifted across so that the
        robot tracks ``follow_distance`` from the wall (the paper's target
        when it already is at that distance).
        """
        p = self.params
        heading = float(pose[2])
        # the followed wall: the nearest echo on the wall's side (or just past ahead),
        # not farther than twice the following distance
        a = self.sonar.angles
        on_side = (-self._side * a) >= -p.wall_front_angle
        seen = on_side & (ranges < min(self.sonar.max_range, 2.0 * p.follow_distance))
        L = p.virtual_target_distance
        if not np.any(seen):  # wall lost: turn toward the side it was on
            aim = heading - self._side * 0.5 * math.pi
            return np.array([pose[0] + L * math.cos(aim), pose[1] + L * math.sin(aim)])
        k = int(np.flatnonzero(seen)[np.argmin(ranges[seen])])
        u_dir = heading + float(a[k])
        normal = -np.array([math.cos(u_dir), math.sin(u_dir)])       # wall -> robot
        tangent = np.array([math.cos(u_dir + self._side * 0.5 * math.pi),
                            math.sin(u_dir + self._side * 0.5 * math.pi)])
        echo = pose[:2] - ranges[k] * normal
        return echo + p.follow_distance * normal + L * tangent

    def _update_episode(self, pose: np.ndarray, ranges: np.ndarray, goal: np.ndarray) -> None:
        """Start, continue, end or abandon a wall-following episode."""
        p = self.params
        trapped, blocked, dist = self._trapped(pose, ranges, goal)
        if dist < self._best_dist:
            self._best_dist, self._since_best = dist, 0
        else:
            self._since_best += 1
        if self._side != 0:
            self._episode_steps += 1
            closer = dist < self._entry_dist or not p.leave_closer
            if closer and (not trapped or not blocked):
                self._side, self._last_side = 0, 0
            elif self._episode_steps > p.max_follow_steps:
                # following this way leads nowhere: give up, next time try the other side
                self._side, self._last_side = 0, self._side
                self._since_best = 0
        elif trapped and self._since_best >= p.trap_steps:
            if self._last_side != 0:
                self._side = -self._last_side
            else:
                # the side whose wall tangent is closer to the current heading
                u_dir = float(pose[2] + self.sonar.angles[int(np.argmin(ranges))])
                plus = abs(float(wrap_angle(u_dir + 0.5 * math.pi - pose[2])))
                minus = abs(float(wrap_angle(u_dir - 0.5 * math.pi - pose[2])))
                self._side = 1 if plus <= minus else -1
            self._entry_dist = dist
            self._episode_steps = 0

    def decide(self, pose: np.ndarray, ranges: np.ndarray, goal: np.ndarray) -> NavDecision:
        """Choose the next via-point from the current scan (updates the episode state)."""
        pose = np.asarray(pose, dtype=float)
        goal = np.asarray(goal, dtype=float)
        if self.params.escape:
            self._update_episode(pose, ranges, goal)
        target = goal if self._side == 0 else self._virtual_target(pose, ranges)
        mu, admissible, _ = self.evaluate(pose, ranges, target)
        idx, mu_d = fuzzy_decision(mu, admissible, self.params.weights)
        return NavDecision(v=float(self._v[idx]), omega=float(self._omega[idx]),
                           mu=np.append(mu[idx], mu_d[idx]), escaping=self._side != 0,
                           target=target)


# ---------------------------------------------------------------- the paper's Table 1

TABLE1_MEMBERSHIPS = np.array([
    [0.1, 0.2, 0.1, 0.4, 0.5, 0.25, 0.3],    # muG1
    [0.2, 0.5, 0.05, 0.5, 0.1, 0.3, 0.2],    # muG2
    [0.3, 0.6, 0.4, 0.7, 0.3, 0.6, 0.3],     # muG3
]).T
"""The paper's Table 1: memberships of seven candidates (rows) in G1, G2, G3 (columns)."""
TABLE1_PAPER_MU_D = (0.1, 0.2, 0.05, 0.4, 0.1, 0.25, 0.2)
"""The decision memberships printed in Table 1."""
TABLE1_PAPER_CHOICE = 4
"""The candidate (1-based) the paper chooses from Table 1."""


@dataclass(frozen=True)
class Table1Report:
    """Table 1 recomputed beside the paper's numbers.

    Attributes:
        memberships: (7, 3) the table's muG1, muG2, muG3.
        weights: the goal weights used (all ones: the paper's plain minimum).
        mu_d: (7,) our decision memberships; paper_mu_d: the paper's.
        choice, paper_choice: chosen candidate (1-based), ours and the paper's.
    """

    memberships: np.ndarray
    weights: tuple[float, ...]
    mu_d: np.ndarray
    choice: int
    paper_mu_d: tuple[float, ...] = TABLE1_PAPER_MU_D
    paper_choice: int = TABLE1_PAPER_CHOICE

    @property
    def weighted(self) -> bool:
        """Whether the goals are weighted (then the paper's plain-minimum numbers differ)."""
        return any(w != 1.0 for w in self.weights)

    @property
    def matches(self) -> bool:
        """Whether our decision memberships and choice equal the paper's (to 1e-12)."""
        return (self.choice == self.paper_choice
                and bool(np.allclose(self.mu_d, self.paper_mu_d, rtol=0.0, atol=1e-12)))

    def to_dict(self) -> dict[str, Any]:
        return {"memberships": self.memberships.tolist(), "weights": list(self.weights),
                "mu_d": self.mu_d.tolist(), "choice": self.choice,
                "paper_mu_d": list(self.paper_mu_d), "paper_choice": self.paper_choice,
                "weighted": self.weighted, "matches": self.matches}

    def lines(self) -> list[str]:
        """The table as printed by ``bench fuzzy-table``."""
        out = [f"{'candidate':<12}" + "".join(f"{i + 1:>7}" for i in range(len(self.mu_d)))]
        for j in range(self.memberships.shape[1]):
            out.append(f"{'muG' + str(j + 1):<12}"
                       + "".join(f"{v:>7.3g}" for v in self.memberships[:, j]))
        out.append(f"{'muD paper':<12}" + "".join(f"{v:>7.3g}" for v in self.paper_mu_d))
        out.append(f"{'muD ours':<12}" + "".join(f"{v:>7.3g}" for v in self.mu_d))
        out.append(f"chosen candidate: paper {self.paper_choice}, ours {self.choice} "
                   f"(muD {self.mu_d[self.choice - 1]:.3g}); weights "
                   f"{', '.join(f'{w:.3g}' for w in self.weights)}; "
                   f"{'matches the paper' if self.matches else 'differs from the paper'}")
        return out


def table1(weights: Any = None) -> Table1Report:
    """Recompute the paper's Table 1 with :func:`fuzzy_decision` (``weights``: eq. 1)."""
    w = (1.0, 1.0, 1.0) if weights is None else check_weights("table1.weights", weights, goals=3)
    idx, mu_d = fuzzy_decision(TABLE1_MEMBERSHIPS, weights=w)
    return Table1Report(memberships=TABLE1_MEMBERSHIPS.copy(), weights=tuple(w), mu_d=mu_d,
                        choice=idx + 1)


def reciprocal_matrix(upper: Any) -> np.ndarray:
    """The (m, m) pairwise-comparison matrix from its strict upper triangle, row by row
    (``a12, a13, ..., a1m, a23, ...``): ones on the diagonal, ``a_ji = 1 / a_ij``.

    Raises:
        InputDataError: a count that is not m (m - 1) / 2 for some m >= 2, or a
            value that is not a finite number > 0.
    """
    try:
        u = np.asarray(upper, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputDataError(f"pairwise comparisons must be numbers, got {upper!r}") from None
    m = int(round((1 + math.sqrt(1 + 8 * u.size)) / 2))
    if u.size == 0 or m * (m - 1) // 2 != u.size:
        raise InputDataError(f"the upper triangle of an (m, m) comparison matrix has "
                             f"m (m - 1) / 2 entries (1, 3, 6, ...), got {u.size}")
    if not np.all(np.isfinite(u)) or np.any(u <= 0):
        raise InputDataError(f"pairwise comparisons must be finite numbers > 0, got "
                             f"{u.tolist()}")
    a = np.ones((m, m))
    iu = np.triu_indices(m, 1)
    a[iu] = u
    a[(iu[1], iu[0])] = 1.0 / u
    return a
