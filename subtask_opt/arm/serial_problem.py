"""Sequencing pose targets for any serial arm: order and configuration together.

A :class:`SerialProblem` is built once: every IK solution of every target
(configurations in collision with the scene or the arm itself dropped), then
the legs between all configurations and the home configuration (the joint model,
phase-synchronised: every joint on the straight joint-space line, time-optimal under the
velocity, acceleration and, where the arm has them, jerk limits,
:func:`~subtask_opt.kinematics.joint_moves.joint_leg_times`): the dense matrix, or above
:data:`SPARSE_FROM` configurations the candidate legs of :mod:`subtask_opt.arm.sparse_legs`.

:func:`solve_serial_problem` compiles it into the robot-free
:class:`~subtask_opt.tour.lazy.LazyLegsProblem` (:meth:`SerialProblem.tour_problem`),
whose lazy leg check is :class:`CellLegs` (the collision check and the detour planner),
and solves it with :func:`subtask_opt.tour.solve.solve`, tour home -> targets -> home
(or an open path from home). The straight legs' times are lower bounds of every leg;
the search asks about the legs of its new best tours, and its answer uses verified legs
only (free straight legs and planned detours).

The result's ``leg_times`` and ``total_time`` are the *executed* times:
ruckig's time-optimal profiles of the same straight lines with the arm's jerk limits
(:func:`~subtask_opt.kinematics.joint_moves.joint_move`), equal to the planned times to
round-off.
"""

from __future__ import annotations

import contextvars
import math
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt._kernel_cache import compile_apart
from subtask_opt.arm.report import ArmReport, TourLeg
from subtask_opt.base.errors import InputDataError, ParameterError, require_in_range
from subtask_opt.base.stop import StoppingCriterion, check_time_limit
from subtask_opt.kinematics.joint_moves import (
    JointLimits,
    joint_leg_square,
    joint_leg_times,
    joint_limits,
    ruckig_leg_time,
)
from subtask_opt.tour import clustered as _gc
from subtask_opt.tour.constraints import TourConstraints
from subtask_opt.tour.lazy import LazyLegsProblem, LegVerifier
from subtask_opt.tour.solve import Result
from subtask_opt.tour.sparse import SparseLegs

if TYPE_CHECKING:
    from subtask_opt.arm.targets import Targets
    from subtask_opt.cell.detour import Detour, DetourParams
    from subtask_opt.cell.scene import CollisionChecker, Scene
    from subtask_opt.kinematics.ik import IKParams
    from subtask_opt.kinematics.serial import SerialArm
    from subtask_opt.tour.solve import SolverParams

_PROGRESS: contextvars.ContextVar[bool] = contextvars.ContextVar("serial_build_progress",
                                                                default=False)


@contextmanager
def build_progress(enabled: bool) -> Iterator[None]:
    """Progress bars (on a terminal) for the phases of every :class:`SerialProblem` built
    inside the block: IK, collision checks (per target), legs; the search's own bar is
    ``solve(..., progress=True)``. The CLI wraps the problem's construction in it."""
    token = _PROGRESS.set(bool(enabled))
    try:
        yield
    finally:
        _PROGRESS.reset(token)


@contextmanager
def _ticker(desc: str) -> Iterator[None]:
    from subtask_opt.base.progress import elapsed_ticker

    if not _PROGRESS.get():
        yield
        return
    with elapsed_ticker(desc):
        yield


SPARSE_FROM = 20_000
"""``legs_mode="auto"`` uses the candidate legs above this many configurations (or when
the dense matrix would not fit in memory): up to it, the dense (M, M) matrix and the
micro-GA are kept, so every problem the dense path solved before (it refused more than
20,000 configurations) is solved as before (``benchmarks/scale.py --compare`` measures
both on RoboTSP's subsets and small panels)."""
LEGS_MODES = ("auto", "dense", "sparse")
"""How :class:`SerialProblem` stores its legs (its ``legs_mode``)."""


@contextmanager
def _phase(cpu: dict[str, float], key: str) -> Iterator[None]:
    """The block's CPU time into ``cpu[key]``, its compilation apart (:func:`compile_apart`)."""
    t0 = time.process_time()
    with compile_apart(cpu) as compiled:
        yield
    cpu[key] += time.process_time() - t0 - compiled[0]


@dataclass(frozen=True, eq=False)
class SerialProblem:
    """Pose targets for a serial arm, with a home configuration and optional boxes.

    Attributes:
        targets: the pose targets (:func:`subtask_opt.arm.poses.load_targets`).
        arm: the arm (:func:`subtask_opt.kinematics.serial.load_serial_arm`), with
            acceleration limits.
        home: (n,) home configuration in radians; the tour starts and ends there.
        scene: boxes to avoid (None: self-collision only).
        ik: IK settings (default: every distinct solution modulo 2 pi, no +-2 pi
            alternatives, which would multiply the configurations).
        clearance: (m) legs are swept so that no point of the arm moves more
            than this between two checked configurations.
        check_collisions: check configurations and legs at all.
        ik_seed: seed of the IK's random starts.
        detours: plan a leg in collision around the obstacles (False: forbid it).
        detour: the planner's budgets (default :class:`~subtask_opt.cell.detour.DetourParams`).

    A scene with a ``tool`` mounts it (:meth:`~subtask_opt.cell.scene.Tool.mount`): ``arm``
    becomes the given arm with its tool frame at the tool's TCP, which then reaches the
    targets (the given arm's own tool frame is not used).
        legs_mode: ``"dense"`` the (M, M) leg matrix; ``"sparse"`` candidate legs only
            (:mod:`subtask_opt.arm.sparse_legs`: dominated configurations dropped, at most
            :func:`~subtask_opt.arm.sparse_legs.cap_for` + 1 per target, leg blocks
            between candidate targets, memory linear in the targets); ``"auto"`` (default)
            sparse above :data:`SPARSE_FROM` configurations.
            The only size limit is memory: a problem whose legs would not fit in the
            available memory is refused before any IK.

    :meth:`tour_problem` is what :func:`solve_serial_problem` solves.

    Built on construction (read-only): ``configurations`` (per target, (K_i, n)),
    ``offsets``, ``flat`` (M, n), ``legs`` (M, M, symmetric), ``home_out``/``home_in``
    (M,, equal), ``dist`` (N, N) the cheapest leg between each pair of targets,
    ``penalty`` (the finite time that stands for a leg found in collision: more than
    any tour of possible legs), ``cpu`` (seconds of IK, collision and matrix work, and
    numba's compilation apart) and the collision checker.

    Raises:
        ParameterError: bad home shape, clearance or legs_mode, or legs that would not fit
            in memory.
        InputDataError: home outside the limits or in collision; a target with no
            (collision-free) configuration, naming its row.
    """

    targets: Targets
    arm: SerialArm
    home: Any
    scene: Scene | None = None
    ik: IKParams | None = None
    clearance: float = 0.01
    check_collisions: bool = True
    ik_seed: int = 0
    detours: bool = True
    detour: DetourParams | None = None
    legs_mode: str = "auto"
    configurations: tuple[np.ndarray, ...] = field(init=False, repr=False)
    offsets: np.ndarray = field(init=False, repr=False)
    flat: np.ndarray = field(init=False, repr=False)
    legs: np.ndarray = field(init=False, repr=False)
    dist: np.ndarray = field(init=False, repr=False)
    penalty: float = field(init=False, repr=False)
    home_out: np.ndarray = field(init=False, repr=False)
    home_in: np.ndarray = field(init=False, repr=False)
    limits: JointLimits = field(init=False, repr=False)
    checker: CollisionChecker | None = field(init=False, repr=False)
    cpu: dict[str, float] = field(init=False, repr=False)
    dropped_in_collision: int = field(init=False, repr=False)
    # the candidate legs (legs_mode "sparse"; None: the dense matrix) and the bound's inputs
    sparse: Any = field(init=False, repr=False, default=None)
    bound_inputs: Any = field(init=False, repr=False, default=None)
    dropped_dominated: int = field(init=False, repr=False, default=0)
    dropped_by_cap: int = field(init=False, repr=False, default=0)
    # ``legs`` is a read-only view of this array; solve_serial_problem hands it to the kernels
    # without an M x M copy (a read-only array would be compiled for separately), blocks
    # the legs it finds in collision in place and restores them before it returns, under
    # ``_lock``
    _legs_memory: np.ndarray = field(init=False, repr=False)
    # cheapest leg between each target and each configuration (ConfiguredData.cheapest),
    # writable like ``_legs_memory`` for the same reason
    _cheapest: np.ndarray = field(init=False, repr=False)
    _lock: threading.Lock = field(init=False, repr=False, default_factory=threading.Lock)

    def __post_init__(self) -> None:
        from subtask_opt.arm.targets import Targets, describe
        from subtask_opt.kinematics.ik import IKParams, IKSolver
        from subtask_opt.kinematics.serial import SerialArm

        if not isinstance(self.targets, Targets) or self.targets.planar:
            raise ParameterError(f"SerialProblem.targets must be 3-D Targets, got "
                                 f"{describe(self.targets)}")
        if not isinstance(self.arm, SerialArm):
            raise ParameterError(f"SerialProblem.arm must be a SerialArm, got "
                                 f"{type(self.arm).__name__}")
        require_in_range("SerialProblem", "clearance", self.clearance, 1e-4, 1.0)
        from subtask_opt.cell.detour import DetourParams

        if not isinstance(self.detours, bool):
            raise ParameterError(f"SerialProblem.detours must be a bool, got {self.detours!r}")
        if self.detour is not None and not isinstance(self.detour, DetourParams):
            raise ParameterError(f"SerialProblem.detour must be DetourParams or None, got "
                                 f"{self.detour!r}")
        if self.scene is not None and self.scene.tool is not None:
            object.__setattr__(self, "arm", self.scene.tool.mount(self.arm))
        arm = self.arm
        home = np.asarray(self.home, dtype=np.float64)
        if home.shape != (arm.nq,) or not np.all(np.isfinite(home)):
            raise ParameterError(f"SerialProblem.home must be {arm.nq} finite joint values "
                                 f"(radians) for {arm.name}, got {self.home!r}")
        if not arm.within_limits(home, tol=1e-9):
            bad = int(np.flatnonzero((home < arm.limits.lower - 1e-9)
                                     | (home > arm.limits.upper + 1e-9))[0])
            raise InputDataError(
                f"home joint {bad + 1} = {np.degrees(home[bad]):.4g} deg is outside its limits "
                f"[{np.degrees(arm.limits.lower[bad]):.4g}, "
                f"{np.degrees(arm.limits.upper[bad]):.4g}] deg")
        home.setflags(write=False)
        object.__setattr__(self, "home", home)
        acc = arm.limits.require("acceleration")
        object.__setattr__(self, "limits", joint_limits(arm.limits.velocity, acc,
                                                         arm.limits.jerk))
        cpu: dict[str, float] = {"ik": 0.0, "collision": 0.0, "matrix": 0.0, "compile": 0.0}

        checker = None
        if self.check_collisions:
            t0 = time.process_time()
            checker = (self.scene.for_arm(arm) if self.scene is not None else _self_checker(arm))
            if checker.in_collision(home):
                pairs = ", ".join(f"{a}/{b}" for a, b in checker.colliding_pairs(home)[:3])
                raise InputDataError(f"home {np.degrees(home).round(3).tolist()} deg is in "
                                     f"collision ({pairs})")
            cpu["collision"] += time.process_time() - t0
        object.__setattr__(self, "checker", checker)

        if self.legs_mode not in LEGS_MODES:
            raise ParameterError(f"SerialProblem.legs_mode must be one of {LEGS_MODES}, got "
                                 f"{self.legs_mode!r}")
        params = self.ik if self.ik is not None else IKParams(wrap_alternatives=False)
        mode = _legs_mode(self, params)
        check_time_limit("before the IK")
        poses = self.targets.poses
        assert poses is not None  # 3-D targets (checked above)
        with _phase(cpu, "ik"), _ticker(f"IK of {len(self.targets)} targets"):
            solutions = IKSolver(arm, params).solve_targets(poses, seed=self.ik_seed)
        for i, q in enumerate(solutions.configurations):
            if q.shape[0] == 0:
                point = np.round(self.targets.points[i], 6).tolist()
                raise InputDataError(f"target {i} (row {i + 1}, point {point}) has no IK "
                                     f"solution within the joint limits of {arm.name}")
        if _decide(mode, int(solutions.counts.sum())) == "sparse":
            _build_sparse(self, solutions, checker, cpu)
            return
        from subtask_opt.base.progress import progress_bar

        configs = []
        dropped = 0
        bar = progress_bar(_PROGRESS.get() and checker is not None, total=len(self.targets),
                           desc="collision checks", unit="target")
        for i, q in enumerate(solutions.configurations):
            point = np.round(self.targets.points[i], 6).tolist()
            bar.update(1)
            if checker is not None:
                check_time_limit(f"in the collision checks (target {i + 1} of "
                                 f"{len(self.targets)})")
                t0 = time.process_time()
                free = np.array([not checker.in_collision(c) for c in q], dtype=bool)
                cpu["collision"] += time.process_time() - t0
                dropped += int((~free).sum())
                q = q[free]
                if q.shape[0] == 0:
                    raise InputDataError(f"target {i} (row {i + 1}, point {point}) has no "
                                         f"collision-free configuration (all "
                                         f"{free.size} IK solutions collide)")
            q = np.ascontiguousarray(q)
            q.setflags(write=False)
            configs.append(q)
        bar.close()
        counts = np.array([q.shape[0] for q in configs], dtype=np.int64)
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        flat = np.ascontiguousarray(np.vstack(configs))
        check_time_limit(f"before the legs between {flat.shape[0]} configurations")
        with _phase(cpu, "matrix"), _ticker(f"legs between {flat.shape[0]} configurations"):
            memory = joint_leg_square(flat, self.limits)
            legs = memory.view()
            home_out = joint_leg_times(home, flat, self.limits)[0]
            home_in = home_out.copy()  # a leg takes as long either way
            dist, cheapest, top = _gc.block_minima(memory, offsets)
        check_time_limit(f"in the legs between {flat.shape[0]} configurations")
        penalty = (len(configs) + 2) * max(float(top), float(home_out.max())) + 1.0
        for name, value in (("configurations", tuple(configs)), ("offsets", offsets),
                            ("flat", flat), ("legs", legs), ("dist", dist),
                            ("penalty", penalty), ("home_out", home_out),
                            ("home_in", home_in), ("cpu", cpu), ("_cheapest", cheapest),
                            ("dropped_in_collision", dropped), ("_legs_memory", memory)):
            if isinstance(value, np.ndarray) and value is not memory and value is not cheapest:
                value.setflags(write=False)
            object.__setattr__(self, name, value)

    def tour_problem(self, verifier: LegVerifier | None = None) -> LazyLegsProblem:
        """The robot-free problem :func:`subtask_opt.tour.solve.solve` searches: the
        configurations its nodes (flat indices), the planned legs its legs (the dense
        matrix, written in place by the search and restored, or the candidate legs, whose
        blocks ``extend`` adds to this problem), ``verifier`` the lazy leg check."""
        if self.sparse is None:
            return LazyLegsProblem(self.offsets, self.home_out, self.penalty,
                                   legs=self._legs_memory, dist=self.dist,
                                   cheapest=self._cheapest, verifier=verifier)
        return LazyLegsProblem(self.offsets, self.home_out, self.penalty, sparse=self.sparse,
                               bound_inputs=self.bound_inputs,
                               extend=lambda pairs: _add_pairs(self, pairs), verifier=verifier)

    @property
    def size(self) -> int:
        """Number of targets."""
        return len(self.configurations)

    @property
    def counts(self) -> np.ndarray:
        """(N,) configurations per target."""
        return np.diff(self.offsets)


def _self_checker(arm: SerialArm) -> CollisionChecker:
    from subtask_opt.cell.scene import CollisionChecker

    return CollisionChecker(arm)


def _legs_mode(problem: SerialProblem, params: IKParams) -> str:
    """The legs mode before any work, its memory checked against what is available: at
    most 8 IK solutions per tool pose (the closed forms; times 2^n with the +-2 pi
    alternatives) bound the configurations. "auto" stays undecided until the IK has
    counted them (:func:`_decide`)."""
    from subtask_opt.arm import sparse_legs as sl

    targets = problem.targets
    per_pose = 8 * (2 ** problem.arm.nq if params.wrap_alternatives else 1)
    most = targets.n_candidates * per_pose
    if problem.legs_mode == "dense":
        sl.check_memory(_dense_bytes(most))
    else:  # sparse, or auto (which goes sparse whenever the dense matrix would not fit)
        sl.check_memory(sl.memory_estimate(most, len(targets), cap=_cap(problem)))
    return problem.legs_mode


def _cap(problem: SerialProblem) -> int:
    """Configurations a target of ``problem`` keeps on candidate legs
    (:func:`~subtask_opt.arm.sparse_legs.cap_for`)."""
    from subtask_opt.arm import sparse_legs as sl

    scene = problem.scene
    obstacles = scene is not None and bool(scene.boxes or scene.meshes)
    return sl.cap_for(len(problem.targets), obstacles)


def _dense_bytes(m: int) -> int:
    """Bytes of the dense legs of m configurations: the (M, M) matrix and its copies of
    block minima (about 1.5 matrices at the peak)."""
    return int(12 * m * m)


def _decide(mode: str, m: int) -> str:
    """"auto": dense up to :data:`SPARSE_FROM` configurations
    when the matrix fits in the available memory, sparse otherwise."""
    from subtask_opt.arm import sparse_legs as sl

    if mode != "auto":
        return mode
    free = sl.available_memory()
    if m > SPARSE_FROM or (free is not None and _dense_bytes(m) > free):
        return "sparse"
    return "dense"


def _build_sparse(problem: SerialProblem, solutions: Any, checker: Any,
                  cpu: dict[str, float]) -> None:
    """The candidate legs of :mod:`subtask_opt.arm.sparse_legs` into ``problem``: dominated
    configurations dropped (exact), the rest checked for collisions, the bound's inputs
    over every free configuration, each target's best ``_cap(problem)`` free ones kept
    (+ the one nearest the home), leg blocks between candidate targets."""
    from subtask_opt.arm import sparse_legs as sl

    lim = problem.limits
    home = problem.home
    raw = [np.asarray(q) for q in solutions.configurations]
    counts = np.array([q.shape[0] for q in raw], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    flat = np.ascontiguousarray(np.vstack(raw))
    assert problem.targets.poses is not None  # 3-D targets (SerialProblem checks them)
    points = np.array([p[0, :3, 3] for p in problem.targets.poses])
    with _phase(cpu, "matrix"), _ticker("configurations: dominance"):
        rev = problem.arm.revolute
        canon = np.where(rev, np.mod(flat + math.pi, 2 * math.pi), flat).round(6)
        _, group = np.unique(canon, axis=0, return_inverse=True)
        drop = sl.dominated(flat, offsets, group.astype(np.int64).ravel(), home)
        keep = ~drop
        home_all = joint_leg_times(home, flat, lim)[0]
        f1, o1, h1 = _subset(flat, offsets, keep, home_all)
    dropped = 0
    if checker is not None:  # every configuration, so that the cap chooses among free ones
        from subtask_opt.base.progress import progress_bar

        t0 = time.process_time()
        free = np.zeros(f1.shape[0], dtype=bool)
        bar = progress_bar(_PROGRESS.get(), total=o1.shape[0] - 1, desc="collision checks",
                           unit="target")
        for t in range(o1.shape[0] - 1):
            bar.update(1)
            check_time_limit(f"in the collision checks (target {t + 1} of {o1.shape[0] - 1})")
            rows = np.arange(o1[t], o1[t + 1])
            free[rows] = [not checker.in_collision(q) for q in f1[rows]]
            if not free[rows].any():
                point = np.round(problem.targets.points[t], 6).tolist()
                raise InputDataError(f"target {t} (row {t + 1}, point {point}) has no "
                                     f"collision-free configuration (all {rows.size} "
                                     "IK solutions collide)")
        bar.close()
        dropped = int((~free).sum())
        cpu["collision"] += time.process_time() - t0
        f1, o1, h1 = _subset(f1, o1, free, h1)
    with _phase(cpu, "matrix"), _ticker("configurations: cap, bound legs"):
        bound = sl.bound_inputs(f1, o1, points, h1, lim, sl.reach_levers(problem.arm),
                                k_bound=BOUND_NEIGHBOURS)
        cap_keep = sl.keep_best(f1, o1, points, h1, lim, _cap(problem))
    f2, o2, h2 = _subset(f1, o1, cap_keep, h1)
    check_time_limit(f"before the candidate legs of {o2.shape[0] - 1} targets")
    with _phase(cpu, "matrix"), _ticker(f"candidate legs of {o2.shape[0] - 1} targets"):
        penalty = _sparse_penalty(f2, o2, h2, lim)
        data = sl.build_sparse(f2, o2, points, h2, lim, penalty=penalty)
    check_time_limit(f"in the candidate legs of {o2.shape[0] - 1} targets")
    configs = tuple(np.ascontiguousarray(f2[o2[t]:o2[t + 1]]) for t in range(o2.shape[0] - 1))
    for q in configs:
        q.setflags(write=False)
    f2.setflags(write=False)
    h2 = h2.copy()
    h2.setflags(write=False)
    empty = np.zeros((0, 0))
    for name, value in (("configurations", configs), ("offsets", o2), ("flat", f2),
                        ("legs", empty), ("dist", empty), ("penalty", penalty),
                        ("home_out", h2), ("home_in", h2), ("cpu", cpu),
                        ("_cheapest", empty), ("dropped_in_collision", dropped),
                        ("_legs_memory", empty), ("sparse", data), ("bound_inputs", bound),
                        ("dropped_dominated", int(drop.sum())),
                        ("dropped_by_cap", int(f1.shape[0] - cap_keep.sum()))):
        object.__setattr__(problem, name, value)


def _subset(flat: np.ndarray, offsets: np.ndarray, keep: np.ndarray,
            home: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The configurations with ``keep``, their offsets and home legs."""
    counts = np.add.reduceat(keep.astype(np.int64), offsets[:-1])
    return (np.ascontiguousarray(flat[keep]),
            np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
            np.ascontiguousarray(home[keep]))


def _sparse_penalty(flat: np.ndarray, offsets: np.ndarray, home: np.ndarray,
                    limits: JointLimits) -> float:
    """A leg time longer than any tour of possible legs: targets + 2 times the longest
    possible leg (every joint across its whole range of the configurations)."""
    span = np.vstack([flat.max(axis=0), flat.min(axis=0)])
    top = float(joint_leg_times(span[0], span[1], limits)[0, 0])
    return (offsets.shape[0] + 2) * max(top, float(home.max())) + 1.0


def _add_pairs(problem: SerialProblem, pairs: list[tuple[int, int]]) -> SparseLegs:
    """Add the leg blocks of target ``pairs`` to a sparse problem (the legs a search
    asked for), keeping the legs already marked; returns the new candidate legs."""
    from subtask_opt.arm import sparse_legs as sl

    sp = problem.sparse
    new = [(a, b) for a, b in pairs if a != b and not np.any(sp.nbr[a] == b)]
    if not new:
        return sp
    old = {(a, int(b)): s for a in range(sp.size) for s, b in enumerate(sp.nbr[a]) if b >= 0}
    data = sl.build_sparse(problem.flat, problem.offsets, sp.coords, sp.home, problem.limits,
                           extra=list(old) + new, k_task=0, k_joint=0, penalty=sp.penalty)
    counts = np.diff(problem.offsets)
    for (a, b), s in old.items():  # carry the marked legs over
        size = int(counts[a] * counts[b])
        t = int(np.flatnonzero(data.nbr[a] == b)[0])
        data.legs[data.start[a, t]:data.start[a, t] + size] = sp.legs[sp.start[a, s]:
                                                                      sp.start[a, s] + size]
    object.__setattr__(problem, "sparse", data)
    return data


@dataclass(frozen=True, eq=False)
class SerialReport(ArmReport):
    """What a serial arm's tour means for the arm (``Result.report``,
    :func:`solve_serial_problem`; the :class:`~subtask_opt.arm.report.ArmReport` of every
    robot, with its ``legs`` built from the arrays below).

    Attributes:
        order: (N,) target indices in visiting order (home before the first, after the last).
        configuration_index: (N,) per target (input order), the index of its chosen
            configuration among ``problem.configurations[i]``.
        configurations: (N, n) the chosen joint vector of each target, input order.
        home: (n,) home configuration (radians).
        leg_times: (N + 1,) executed (ruckig) time of each leg: home -> order[0], ...,
            order[-1] -> home.
        planned_leg_times: (N + 1,) the same legs' planned times (the search's model).
        total_time: sum of ``leg_times`` (s).
        collision_checked: whether configurations and the tour's legs were checked.
        counts: targets, configurations per target, legs checked, legs infeasible (in
            collision as straight lines), legs planned (``legs_planned``, of
            ``plan_budget``; ``legs_plan_found`` succeeded), legs detoured (in this
            tour), configurations dropped in collision, search rounds (of the lazy leg
            check) and how many of them ran the GA.
        cpu: CPU seconds of IK, collision checks, matrix, search, and apart from them
            numba's compilation (or loading compiled code) on a first run.
        generations, restarts: what the micro-GA did (summed over rounds).
        seed: the seed.
        open_path: the tour ends at its last target (no leg back home).
        problem: the problem the tour belongs to (for :func:`subtask_opt.trajectory`).
        detours: leg index -> (k, n) waypoints (both ends included, in driving order) of
            each leg planned around an obstacle; the other legs are straight.
    """

    order: np.ndarray
    configuration_index: np.ndarray
    configurations: np.ndarray
    home: np.ndarray
    leg_times: np.ndarray
    planned_leg_times: np.ndarray
    total_time: float
    collision_checked: bool
    counts: dict[str, Any]
    cpu: dict[str, float]
    generations: int
    restarts: int
    seed: int
    open_path: bool = False
    problem: Any = field(default=None, repr=False, compare=False)
    detours: dict[int, np.ndarray] = field(default_factory=dict, repr=False)

    time_model = "joint"
    configurations_mode = "optimize"  # one of every target's IK solutions, chosen

    @property
    def robot(self) -> str:  # type: ignore[override]
        return str(self.problem.arm.name) if self.problem is not None else "?"

    @property
    def legs(self) -> tuple[TourLeg, ...]:  # type: ignore[override]
        """The driven legs (the home is stop -1): executed times, distances between the
        tool points (m), configuration indices at both ends (0 at the home)."""
        stops = [-1] + [int(i) for i in self.order] + ([] if self.open_path else [-1])
        index = [0 if k < 0 else int(self.configuration_index[k]) for k in stops]
        path = self.tour_configurations()
        tips = np.array([self.problem.arm.fk(q)[:3, 3] for q in path]) if (
            self.problem is not None) else np.zeros((len(path), 3))
        return tuple(TourLeg(k, stops[k], stops[k + 1], (index[k], index[k + 1]),
                             float(np.linalg.norm(tips[k + 1] - tips[k])),
                             float(self.leg_times[k]), "joint")
                     for k in range(len(stops) - 1))

    def header(self, n: int) -> str:
        """The summary's first line for ``n`` targets."""
        return f"{n} targets, joint time model, robot {self.robot}"

    def order_lines(self, order: np.ndarray) -> list[str]:
        """The summary's lines after the order."""
        c = self.counts
        per = c["configurations_per_target"]
        cpu = ", ".join(f"{k} {v:.3f} s" for k, v in self.cpu.items())
        return [
            f"{sum(per)} configurations ({min(per)}-{max(per)} per target); executed "
            f"{self.total_time:.4f} s (ruckig), planned {self.planned_time:.4f} s",
            f"legs checked {c['legs_checked']}, in collision {c['legs_infeasible']}, "
            f"detoured {c['legs_detoured']}" + (
                f" (planned {c['legs_planned']} of budget {c['plan_budget']}, found "
                f"{c['legs_plan_found']}, planner {self.cpu.get('planner', 0.0):.3f} s CPU)"
                if c.get("detours") else " (detours off)" if "detours" in c else "")
            + ("" if self.collision_checked else " (collisions not checked)"),
            f"CPU: {cpu}",
        ]

    def leg_table(self) -> str:
        """One row per leg: from, to, planned and executed time."""
        names = ["home"] + [str(int(i)) for i in self.order] + (
            [] if self.open_path else ["home"])
        rows = [" leg  from    to  planned [s]  executed [s]"]
        for k, (a, b) in enumerate(zip(names[:-1], names[1:], strict=True)):
            rows.append(f"{k:4d} {a:>5} {b:>5} {self.planned_leg_times[k]:12.4f} "
                        f"{self.leg_times[k]:13.4f}")
        return "\n".join(rows)

    def warning(self) -> str | None:
        """Nothing to warn about (legs in collision are never in an answer)."""
        return None

    @property
    def planned_time(self) -> float:
        """Sum of the planned times of the tour's legs (s)."""
        return float(self.planned_leg_times.sum())

    def tour_configurations(self) -> np.ndarray:
        """(N + 2, n) joint vectors in tour order: home, targets, home (open: no return)."""
        return np.vstack([self.home, self.configurations[self.order]]
                         + ([] if self.open_path else [self.home]))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (the CLI's ``--json``); joint values in radians."""
        return {
            **self.common_dict(),
            "order": [int(i) for i in self.order],
            "configurations": self.configurations.tolist(),
            "configuration_index": [int(i) for i in self.configuration_index],
            "home": self.home.tolist(),
            "leg_times": self.leg_times.tolist(),
            "planned_leg_times": self.planned_leg_times.tolist(),
            "total_time": self.total_time,
            "planned_time": self.planned_time,
            "collision_checked": self.collision_checked,
            "counts": self.counts,
            "cpu_s": self.cpu,
            "generations": self.generations,
            "restarts": self.restarts,
            "seed": self.seed,
            "open_path": self.open_path,
            "detours": {str(k): w.tolist() for k, w in sorted(self.detours.items())},
            "units": {"time": "s", "joints": "rad"},
        }


CLUTTERED_SHARE = 0.25
"""A search that verifies its new bests' legs gives that up once they have taken more than
this share of the plan budget (``DetourParams.max_plans``): the cell is cluttered, and the
search starts again verifying whole answers' legs (:meth:`CellLegs.crowded`)."""
BOUND_NEIGHBOURS = 40
"""Nearest pairs (task space) per target whose cheapest leg the sparse bound computes
exactly. With the Cartesian bound of the other pairs alone, 60 left a 2,000-hole panel's
bound 9% lower than 120 (it is then below the tour's typical leg); with their joint-space
bound as well (:func:`~subtask_opt.arm.sparse_legs.far_joint_bound`) 40 gives the bound of
120 on the 500-, 2,000- and 5,000-hole panels (108.728, 307.318, 610.004 s) for less
CPU (5,000 holes: 67.9 -> 55.5 s)."""


class CellLegs(LegVerifier):
    """The lazy-cost hook of a serial arm in its cell: a straight joint-space leg is swept
    against the scene (:meth:`~subtask_opt.cell.scene.CollisionChecker.leg_in_collision`
    with the problem's clearance); one in collision is planned around the obstacles
    (:func:`~subtask_opt.cell.detour.plan_detour`: OMPL's RRTConnect, simplified, timed
    through its waypoints, one attempt) and costs the detour's planned time, or, when the
    planner fails, its budget (``DetourParams.max_plans`` per solve) is spent or detours
    are off, is impossible.

    Attributes:
        detours: (lo, hi) flat indices (-1 the home) -> the detour planned for that leg.
        plans: plans made so far.
        cpu: CPU seconds of the collision checks (``collision``) and of the planner
            (``planner``).
    """

    def __init__(self, problem: SerialProblem, seed: int) -> None:
        from subtask_opt.cell.detour import DetourParams

        assert problem.checker is not None
        self.problem = problem
        self.seed = seed
        self.params = problem.detour if problem.detour is not None else DetourParams()
        self.detours: dict[tuple[int, int], Detour] = {}
        self.plans = 0
        self.cpu = {"collision": 0.0, "planner": 0.0}

    def verify(self, a: int, b: int) -> float | None:
        from subtask_opt.cell.detour import plan_detour

        p = self.problem
        assert p.checker is not None
        t0 = time.process_time()
        q_lo = p.home if a < 0 else p.flat[a]
        q_hi = p.flat[b]
        collides = p.checker.leg_in_collision(q_lo, q_hi, p.clearance)
        t1 = time.process_time()
        self.cpu["collision"] += t1 - t0
        if not collides:
            return None
        if not p.detours or self.plans >= self.params.max_plans:
            return math.inf
        self.plans += 1
        detour = plan_detour(p.checker, q_lo, q_hi, clearance=p.clearance, limits=p.limits,
                             jerk=p.arm.limits.jerk, seed=self.seed, params=self.params,
                             attempts=1)
        self.cpu["planner"] += time.process_time() - t1
        if detour is None:
            return math.inf
        self.detours[(a, b)] = detour
        return float(detour.planned_time)

    def crowded(self) -> bool:
        return self.problem.detours and self.plans > self.params.max_plans * CLUTTERED_SHARE

    def forget(self) -> None:
        self.detours.clear()
        self.plans = 0


def solve_serial_problem(problem: SerialProblem, *, seed: int = 0,
                         stop: StoppingCriterion | list[StoppingCriterion] | None = None,
                         params: SolverParams | None = None,
                         constraints: TourConstraints | None = None, progress: bool = False,
                         certify: bool = False, certify_time_limit: float = 60.0) -> Result:
    """Order the targets and pick one configuration each for minimum time, from home.

    The problem compiles into the robot-free :class:`~subtask_opt.tour.lazy.LazyLegsProblem`
    (the configurations its nodes, the planned joint-move times its legs, the collision
    check and detour planner its :class:`CellLegs` verifier) and
    :func:`subtask_opt.tour.solve.solve` searches it (:func:`~subtask_opt.tour.lazy.solve_lazy`:
    the tour shapes, precedence, the lazy leg check, the bound and the certificate). The
    answer's detours are then planned again with ``DetourParams.attempts`` attempts (the
    faster kept), and its legs driven by ruckig.

    The legs found in collision are blocked in the problem's leg matrix during the call
    (an M x M copy would cost as much as the search) and restored before it returns;
    concurrent calls on one problem wait for each other.

    Returns:
        A :class:`~subtask_opt.tour.solve.Result` whose ``leg_times``/``total_time`` are
        the executed (ruckig) times, ``configurations`` the (N, n) joint vectors (input
        order) and ``report`` the :class:`SerialReport` (planned times, counts).

    Raises:
        ParameterError: a bad seed, params or constraints, or options that do not apply.
        NoPathError: no tour avoids the legs found in collision.
    """
    from subtask_opt.cell.detour import DetourParams
    from subtask_opt.tour.solve import check_seed, solve

    if not isinstance(problem, SerialProblem):
        raise ParameterError(f"solve_serial_problem needs a SerialProblem, got "
                             f"{type(problem).__name__}")
    seed = check_seed(seed)
    verifier = CellLegs(problem, seed) if problem.checker is not None else None
    with problem._lock:
        found = solve(problem.tour_problem(verifier), seed=seed, stop=stop, params=params,
                      constraints=constraints, progress=progress, certify=certify,
                      certify_time_limit=certify_time_limit)
    order = found.order
    index = np.asarray(found.configurations, dtype=np.int64)
    open_path = found.constraints.tour == "open"
    cpu = dict(problem.cpu)
    cpu["compile"] += found.cpu["compile"]
    cpu["search"] = found.cpu["search"]
    if "bound" in found.cpu:
        cpu["bound"] = found.cpu["bound"]
    detours = verifier.detours if verifier is not None else {}
    if verifier is not None:
        cpu["collision"] += verifier.cpu["collision"]
    cpu["planner"] = verifier.cpu["planner"] if verifier is not None else 0.0
    if "certify" in found.cpu:
        cpu["certify"] = found.cpu["certify"]
    detour_params = problem.detour if problem.detour is not None else DetourParams()
    chosen, _path, planned, executed = _tour_legs(problem, order, index, open_path)
    off = problem.offsets
    nodes = [-1] + [int(off[t] + index[t]) for t in order] + ([] if open_path else [-1])
    _refine_detours(problem, nodes, detours, detour_params, seed, cpu)
    waypoints = _detour_legs(nodes, detours, planned, executed)
    counts: dict[str, Any] = {
        "targets": problem.size,
        "configurations_per_target": [int(k) for k in problem.counts],
        "configurations": int(off[-1]),
        "dropped_in_collision": problem.dropped_in_collision,
    }
    if problem.sparse is not None:
        counts.update(dropped_dominated=problem.dropped_dominated,
                      dropped_by_cap=problem.dropped_by_cap,
                      candidate_legs=found.counts["candidate_legs"])
    counts.update({
        "legs_checked": found.counts["legs_checked"],
        "legs_infeasible": found.counts["legs_infeasible"],
        "legs_planned": verifier.plans if verifier is not None else 0,
        "legs_plan_found": len(detours),
        "legs_detoured": len(waypoints),
        "detours": problem.detours,
        "plan_budget": detour_params.max_plans if problem.detours else 0,
        "search_rounds": found.counts["search_rounds"],
        "ga_rounds": found.counts["ga_rounds"],
    })
    if "kicks" in found.counts:
        counts["kicks"] = found.counts["kicks"]
    report = SerialReport(order=order, configuration_index=index, configurations=chosen,
                          home=np.array(problem.home), leg_times=executed,
                          planned_leg_times=planned, total_time=float(executed.sum()),
                          collision_checked=problem.checker is not None, counts=counts,
                          cpu=cpu, generations=found.generations, restarts=found.restarts,
                          seed=found.seed, open_path=open_path, problem=problem,
                          detours=waypoints)
    return replace(found, total_time=float(executed.sum()), leg_times=executed,
                   report=report, configurations=chosen, cpu=cpu)



def _refine_detours(problem: SerialProblem, nodes: list[int],
                    detours: dict[tuple[int, int], Detour], params: DetourParams, seed: int,
                    cpu: dict[str, float]) -> None:
    """Plan the detours of the answer through ``nodes`` again with ``params.attempts``
    attempts, keeping the faster (the search planned each with one)."""
    from subtask_opt.cell.detour import plan_detour

    t0 = time.process_time()
    for a, b in zip(nodes[:-1], nodes[1:], strict=True):
        key = (min(a, b), max(a, b))
        if key in detours and params.attempts > 1 and problem.checker is not None:
            better = plan_detour(problem.checker, detours[key].waypoints[0],
                                 detours[key].waypoints[-1], clearance=problem.clearance,
                                 limits=problem.limits, jerk=problem.arm.limits.jerk,
                                 seed=seed, params=params)
            if better is not None and better.executed_time < detours[key].executed_time:
                detours[key] = better
    cpu["planner"] += time.process_time() - t0


def _detour_legs(nodes: list[int], detours: dict[tuple[int, int], Detour],
                 planned: np.ndarray, executed: np.ndarray) -> dict[int, np.ndarray]:
    """The waypoints of every detoured leg of the tour through ``nodes`` (flat indices,
    -1 the home), keyed by leg index; ``planned``/``executed`` take the detours' times."""
    out = {}
    for k, (a, b) in enumerate(zip(nodes[:-1], nodes[1:], strict=True)):
        found = detours.get((min(a, b), max(a, b)))
        if found is None:
            continue
        planned[k] = found.planned_time
        executed[k] = found.executed_time
        out[k] = found.waypoints if a == min(a, b) else found.waypoints[::-1].copy()
    return out


def _tour_legs(problem: SerialProblem, order: np.ndarray, choice: np.ndarray,
               open_path: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The chosen configurations (input order), the joint path home -> ... -> home (open:
    no return), and each leg's planned and executed (ruckig) time."""
    n = problem.size
    chosen = np.array([problem.configurations[i][choice[i]] for i in range(n)])
    path = np.vstack([problem.home, chosen[order]] + ([] if open_path else [problem.home]))
    legs = len(path) - 1
    planned = np.array([joint_leg_times(path[k], path[k + 1], problem.limits)[0, 0]
                        for k in range(legs)])
    lim = problem.arm.limits
    executed = np.array([ruckig_leg_time(path[k], path[k + 1], lim.velocity,
                                         problem.limits.acceleration, lim.jerk)
                         for k in range(legs)])
    return chosen, path, planned, executed


def evaluate_tour(problem: SerialProblem, order: Any, choice: Any, *, seed: int = 0,
                  cpu: dict[str, float] | None = None) -> SerialReport:
    """The :class:`SerialReport` of a given tour (another method's answer, say).

    Args:
        order: (N,) permutation of the targets (home before the first, after the last).
        choice: (N,) per target (input order), the index of its configuration.
    """
    n = problem.size
    o = np.asarray(order, dtype=np.int64)
    c = np.asarray(choice, dtype=np.int64)
    if o.shape != (n,) or not np.array_equal(np.sort(o), np.arange(n)):
        raise ParameterError(f"order must be a permutation of 0..{n - 1}, got {order!r}")
    if c.shape != (n,) or np.any(c < 0) or np.any(c >= problem.counts):
        raise ParameterError(f"choice must hold one configuration index per target, got "
                             f"{choice!r}")
    chosen, path, planned, executed = _tour_legs(problem, o, c)
    colliding = 0
    if problem.checker is not None:
        colliding = sum(problem.checker.leg_in_collision(path[k], path[k + 1], problem.clearance)
                        for k in range(n + 1))
    counts = {
        "targets": n,
        "configurations_per_target": [int(k) for k in problem.counts],
        "configurations": int(problem.offsets[-1]),
        "dropped_in_collision": problem.dropped_in_collision,
        "legs_checked": n + 1 if problem.checker is not None else 0,
        "legs_infeasible": int(colliding),
        "legs_detoured": 0,
        "search_rounds": 0,
    }
    return SerialReport(problem=problem, order=o, configuration_index=c, configurations=chosen,
                        home=np.array(problem.home), leg_times=executed,
                        planned_leg_times=planned, total_time=float(executed.sum()),
                        collision_checked=problem.checker is not None, counts=counts,
                        cpu=dict(cpu or {}), generations=0, restarts=0, seed=int(seed))


def default_home(arm: SerialArm) -> np.ndarray | None:
    """The home (radians) the robot's JSON file beside its URDF gives as ``home_deg``, or None."""
    import json

    path = arm.urdf_path.with_suffix(".json")
    if not path.is_file():
        from subtask_opt.kinematics.serial import robots_dir

        path = robots_dir() / f"{arm.name}.json"
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    home = doc.get("home_deg") if isinstance(doc, dict) else None
    if home is None:
        return None
    return np.radians(np.asarray(home, dtype=np.float64))


__all__ = ["LEGS_MODES", "SPARSE_FROM", "SerialProblem", "SerialReport", "build_progress",
           "default_home", "evaluate_tour", "solve_serial_problem"]
