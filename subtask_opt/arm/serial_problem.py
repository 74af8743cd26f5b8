"""Sequencing pose targets for any serial arm: order and configuration together.

A :class:`SerialProblem` is built once: every IK solution of every target
(configurations in collision with the scene or the arm itself dropped), then
the matrix of joint-space leg times between all configurations and the home
configuration (the joint model, phase-synchronised: every joint on the straight
joint-space line, time-optimal under the velocity, acceleration and, where the arm has
them, jerk limits, :func:`~subtask_opt.kinematics.joint_moves.joint_leg_times`).
:func:`solve_serial_problem` searches the order and one configuration per target
together (a generalised TSP on the shared micro-GA core, decoded exactly by a
layered shortest path, :mod:`subtask_opt.tour.clustered`), tour
home -> targets -> home.

Legs are checked for collisions lazily, as GLNS's lazy-edge search evaluates only the
edges its best tour uses: the straight legs' times are lower bounds of every leg; every
new best tour of the search has its legs not checked before swept
(:meth:`~subtask_opt.cell.scene.CollisionChecker.leg_in_collision` with the problem's
clearance); a leg in collision is planned around the obstacles
(:func:`~subtask_opt.cell.detour.plan_detour`: OMPL's RRTConnect, simplified, timed
through its waypoints) and its cost becomes the detour's time, or, when the planner fails
or its budget (``DetourParams.max_plans`` per solve) is spent, or ``detours=False``, it is
marked *infeasible* (a large finite penalty, so the GA avoids it). The GA evaluates its
population again on the corrected costs and searches on, so its answer uses only
verified legs (free straight legs and planned detours; in a cell so cluttered that this
takes much of the plan budget, the answers' legs are checked after each search instead:
:func:`solve_serial_problem`).

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
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt._kernel_cache import compile_seconds
from subtask_opt.arm.report import ArmReport, TourLeg
from subtask_opt.base.errors import (
    InputDataError,
    NoPathError,
    ParameterError,
    SubtaskOptError,
    require_in_range,
    require_int,
)
from subtask_opt.base.stop import Progress, StoppingCriterion, as_criteria, check_time_limit
from subtask_opt.chromosomes import use
from subtask_opt.kinematics.joint_moves import (
    JointLimits,
    joint_leg_square,
    joint_leg_times,
    joint_limits,
    ruckig_leg_time,
)
from subtask_opt.tour import clustered as _gc
from subtask_opt.tour.constraints import Canonical, TourConstraints
from subtask_opt.tour.solve import Result

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
def _compile_apart(cpu: dict[str, float]) -> Iterator[list[float]]:
    """numba's compilation inside the block into ``cpu["compile"]`` (a first run's
    compile is not IK, matrix or search work); the yielded list receives those CPU
    seconds, for the phase the block belongs to to leave out."""
    t0 = time.process_time()
    spent: list[float] = []
    with compile_seconds() as compiled:
        yield spent
    spent.append(min(compiled[0], time.process_time() - t0))
    cpu["compile"] += spent[0]


@contextmanager
def _phase(cpu: dict[str, float], key: str) -> Iterator[None]:
    """The block's CPU time into ``cpu[key]``, its compilation apart (:func:`_compile_apart`)."""
    t0 = time.process_time()
    with _compile_apart(cpu) as compiled:
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

    The lazy leg check (after a search) reads and marks legs through :meth:`leg_time` and
    :meth:`mark_leg` (flat configuration indices, -1 the home), which work for dense and
    sparse legs alike.

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

    def leg_time(self, a: int, b: int) -> float:
        """The planned time of the leg between flat configurations a and b (-1: the home),
        as the search sees it (a leg marked by :meth:`mark_leg` has its marked time).
        The interface of the lazy leg check, either legs_mode."""
        if a < 0 and b < 0:
            return 0.0
        if a < 0 or b < 0:
            return float(self.home_out[max(a, b)])
        if self.sparse is None:
            return float(self._legs_memory[a, b])
        from subtask_opt.tour.sparse import leg

        ta, tb = (int(np.searchsorted(self.offsets, x, side="right") - 1) for x in (a, b))
        return float(leg(self.sparse, ta, a - self.offsets[ta], tb, b - self.offsets[tb]))

    def mark_leg(self, a: int, b: int, value: float) -> float:
        """Set the leg between flat configurations a and b (-1: the home) to ``value``
        both ways (``self.penalty``: infeasible; a detour's time: corrected); returns its
        previous time. A sparse problem adds the targets' block first when it has none.
        Home legs and dense legs are written in place (solve_serial_problem restores the
        dense ones it marks before it returns)."""
        old = self.leg_time(a, b)
        if a < 0 or b < 0:
            self.home_out.setflags(write=True)
            self.home_out[max(a, b)] = value
            self.home_out.setflags(write=False)
            if self.sparse is not None:
                self.sparse.home[max(a, b)] = value
            return old
        if self.sparse is None:
            self._legs_memory[a, b] = self._legs_memory[b, a] = value
            return old
        off = self.offsets
        ta, tb = (int(np.searchsorted(off, x, side="right") - 1) for x in (a, b))
        _add_pairs(self, [(ta, tb)])
        sp = self.sparse
        for u, cu, v, cv in ((ta, a - off[ta], tb, b - off[tb]), (tb, b - off[tb], ta,
                                                                  a - off[ta])):
            slot = int(np.flatnonzero(sp.nbr[u] == v)[0])
            sp.legs[sp.start[u, slot] + cu * (off[v + 1] - off[v]) + cv] = value
        return old

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


def _add_pairs(problem: SerialProblem, pairs: list[tuple[int, int]]) -> None:
    """Add the leg blocks of target ``pairs`` to a sparse problem (the legs a search
    asked for), keeping the legs already marked."""
    from subtask_opt.arm import sparse_legs as sl

    sp = problem.sparse
    new = [(a, b) for a, b in pairs if a != b and not np.any(sp.nbr[a] == b)]
    if not new:
        return
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


MAX_ROUNDS = 200
"""Most GA searches of the lazy leg check before :func:`solve_serial_problem` gives up."""
MAX_REPAIRS = 100
CLUTTERED_SHARE = 0.25
"""A GA that checks its new bests' legs stops once they have taken more than this share of
the plan budget (``DetourParams.max_plans``): the cell is cluttered, and the search starts
again checking whole answers' legs (:func:`solve_serial_problem`)."""


class _Cluttered(Exception):
    """Raised through the GA by its lazy leg check when the cell is cluttered."""
"""Most repair rounds in a row before :func:`solve_serial_problem` runs the GA again."""


def solve_serial_problem(problem: SerialProblem, *, seed: int = 0,
                 stop: StoppingCriterion | list[StoppingCriterion] | None = None,
                 params: SolverParams | None = None, kicks: int | None = None,
                 constraints: TourConstraints | None = None, progress: bool = False,
                 certify: bool = False, certify_time_limit: float = 60.0) -> Result:
    """Order the targets and pick one configuration each for minimum time, from home.

    The tour starts at the problem's home configuration and (``tour="closed"``, the
    default) returns there, or (``tour="open"``) ends at its last target. With a home,
    ``constraints.start`` is the first target and ``constraints.end`` the last one;
    precedence pairs ``(a, b)`` put target a before b. A plain tour searches order and
    configurations together (the clustered GA, decoded exactly by a layered shortest
    path); precedence or a fixed first or last target use the pinned clustered GA
    (:mod:`subtask_opt.tour.pinned_clustered`), which keeps every pair and chooses the
    configurations exactly during the search.

    The micro-GA (``stop``; default ``params.default_stop(n)``, see
    :data:`SERIAL_KICKS`; ``params.runs`` independent runs, default one) checks the legs
    lazily, GLNS-style, as it searches: the unchecked legs of every new best tour are swept
    against the scene when it is found (``run_ga``'s ``on_best``); a leg in collision costs
    its planned detour from then on, or is blocked, the population is evaluated again and
    the search goes on knowing it, so its answer uses checked legs only.
    In a cell so cluttered that those checks take more than :data:`CLUTTERED_SHARE` of the
    plan budget (``DetourParams.max_plans``), the budget is better spent on whole answers'
    legs: the search starts again with every leg unchecked, and the legs are checked after
    each search instead. Then, when the answer uses a leg found in collision, that leg is
    blocked and the same order is decoded again and polished by the local search (a repair
    round: the blocked leg is usually replaced by another configuration of one of its
    targets), until a tour uses no leg found in collision; the GA then runs once more from
    scratch, knowing every leg found so far, and the shorter collision-free answer is kept.
    The GA also runs again when a repair cannot avoid the blocked legs, or after
    :data:`MAX_REPAIRS` repairs in a row.

    The legs found in collision are blocked in the problem's leg matrix during the call
    (an M x M copy would cost as much as the search) and restored before it returns;
    concurrent calls on one problem wait for each other.

    Every answer carries a lower bound: the Held-Karp bound of the cheapest planned leg
    between every two targets (and home), which no tour's planned or executed time is
    below (the planned legs are the executed ones to round-off).
    ``certify`` proves a closed tour without precedence optimal for the planned times by
    the generalised-TSP branch and cut over every configuration (small problems), or
    says why not.

    A problem on candidate legs (``problem.sparse``, legs_mode "sparse") is searched by
    :func:`subtask_opt.tour.sparse.search` instead (an iterated local search: every kick
    counts as one generation for ``stop``; default: :data:`SPARSE_STALL` kicks without
    improvement or :data:`SPARSE_KICKS_PER_TARGET` kicks per target), with the same lazy
    leg check through :meth:`SerialProblem.mark_leg`; its bound is
    :func:`subtask_opt.tour.sparse.one_tree_bound`. Closed tours only; ``certify``,
    ``kicks`` and the micro-GA's ``params`` do not apply there and are refused.

    Args:
        kicks: kicks of the iterated local search per child and restart individual
            (:func:`subtask_opt.tour.permutation.make_aux`); None: its default for N
            targets below ``KICKS_FROM``, :data:`SERIAL_KICKS` from there on (whose default
            stall is then :data:`SERIAL_STALL_SHARE` of the solver's).

    Returns:
        A :class:`~subtask_opt.tour.solve.Result` whose ``leg_times``/``total_time`` are
        the executed (ruckig) times, ``configurations`` the (N, n) joint vectors (input
        order) and ``report`` the :class:`SerialReport` (planned times, counts).

    Raises:
        ParameterError: a bad seed, params, kicks or constraints.
        NoPathError: no tour avoids the legs found in collision.
    """
    from subtask_opt.tour.solve import SolverParams

    if not isinstance(problem, SerialProblem):
        raise ParameterError(f"solve_serial_problem needs a SerialProblem, got "
                             f"{type(problem).__name__}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not (
            0 <= seed < 2**63):
        raise ParameterError(f"seed must be an integer in [0, 2**63), got {seed!r}")
    params = params if params is not None else SolverParams()
    if not isinstance(params, SolverParams):
        raise ParameterError(f"solve_serial_problem: params must be a SolverParams, got {params!r}")
    if kicks is not None:
        require_int("solve_serial_problem", "kicks", kicks, 0, MAX_KICKS)
    require_in_range("solve", "certify_time_limit", certify_time_limit, 1e-3, 86_400.0)
    if problem.sparse is not None:
        if kicks is not None:
            raise ParameterError("kicks applies to the micro-GA of dense legs; a problem on "
                                 "candidate legs (legs_mode 'sparse') has its own kicked search")
        changed = [f for f in ("preset", "population", "convergence_tol", "grasp_share",
                               "max_segment", "neighbours", "paper_loop", "runs", "bound_max_nodes")
                   if getattr(params, f) != getattr(SolverParams(), f)]
        if changed:
            raise ParameterError(f"SolverParams.{changed[0]} applies to the micro-GA of dense "
                                 "legs, not to a problem on candidate legs (legs_mode "
                                 "'sparse')")
        with problem._lock:
            return _solve_sparse(problem, int(seed), stop, params, constraints, progress,
                                 certify)
    shape = _serial_shape(problem, constraints)
    with problem._lock:
        blocked: dict[tuple[int, int], float] = {}  # leg (a, b), a < b -> its time
        try:
            return _search(problem, int(seed), stop, params, kicks, blocked, shape, progress,
                           certify, certify_time_limit)
        finally:
            memory = problem._legs_memory
            for (a, b), value in blocked.items():
                memory[a, b] = memory[b, a] = value


BOUND_NEIGHBOURS = 120
"""Nearest pairs (task space) per target whose cheapest leg the sparse bound computes
exactly (60 left a 2,000-hole panel's bound 9% lower: the closed-form bound of the
other pairs is then below the tour's typical leg)."""
SPARSE_STALL = 5000
"""Kicks without a shorter tour after which the sparse search stops (its default stop,
with :data:`SPARSE_KICKS_PER_TARGET` kicks per target in all)."""
SPARSE_KICKS_PER_TARGET = 20
SPARSE_REPAIR_KICKS = 2000
"""Most kicks of a search round after legs were found in collision, every
:data:`SPARSE_REPAIR_EVERY`-th such round (the others only polish: a round per handful of
legs in collision would otherwise cost kicks each); the first round has the whole
budget; ``stop`` applies to each round, a time limit to all of them."""
SPARSE_REPAIR_EVERY = 10


def _solve_sparse(problem: SerialProblem, seed: int, stop: Any, params: SolverParams,
                  constraints: TourConstraints | None, progress: bool,
                  certify: bool) -> Result:
    """:func:`solve_serial_problem` on candidate legs (:mod:`subtask_opt.tour.sparse`): the
    iterated local search (each kick counts as a generation for ``stop``), the lazy leg
    check (a leg in collision is marked by :meth:`SerialProblem.mark_leg` with its
    detour's time, planned as on the dense matrix within the detour budget, or with the
    penalty, and the search resumes from the same tour), legs between targets that are
    not candidates added when an answer uses one, and the sparse 1-tree bound."""
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.base.results import History
    from subtask_opt.base.stop import MaxGenerations, NoImprovement, Progress
    from subtask_opt.tour import sparse as ts
    from subtask_opt.tour.constraints import checked

    cons = checked(constraints)
    if cons.home is not None or cons.start is not None or cons.end is not None or (
            cons.precedence or cons.tour != "closed"):
        raise ParameterError("a problem on candidate legs (legs_mode 'sparse', more than "
                             "SPARSE_FROM configurations) takes closed tours without a first "
                             "or last target or precedence; use legs_mode='dense' or fewer "
                             "configurations")
    if certify:
        raise ParameterError("certify: the branch and cut needs the dense leg matrix; use "
                             "legs_mode='dense' (small problems)")
    from subtask_opt.cell.detour import DetourParams, plan_detour

    n = problem.size
    cpu = dict(problem.cpu)
    cpu["search"] = 0.0
    cpu["bound"] = 0.0
    cpu["planner"] = 0.0
    detour_params = problem.detour if problem.detour is not None else DetourParams()
    detours: dict[tuple[int, int], Detour] = {}  # legs in collision planned around (lo, hi)
    plans = 0
    kicks = SPARSE_KICKS_PER_TARGET * n + 1000
    criteria = as_criteria(stop, [NoImprovement(SPARSE_STALL), MaxGenerations(kicks)])
    for c in criteria:
        if isinstance(c, MaxGenerations):
            kicks = c.generations
    started = time.monotonic()
    # per search round: its first kick, best time and the kick that found it (a repair
    # round starts afresh: its tour holds legs just blocked, so it is longer than before)
    state: dict[str, Any] = {"best": math.inf, "at": 0, "done": 0, "start": 0}

    def should_stop() -> bool:
        p = Progress(int(state["done"] - state["start"]), float(state["best"]),
                     int(state["done"] - state["at"]),
                     time.monotonic() - started)
        return any(c(p) for c in criteria)

    history_gen: list[int] = []
    history_cost: list[float] = []
    checked_legs: dict[tuple[int, int], bool] = {}
    tour = choice = None
    done_total = rounds = 0
    t0 = time.process_time()
    with _compile_apart(cpu) as compiled, progress_bar(progress, total=kicks,
                                                       desc="search (kicks)",
                                                       unit="kick") as bar:
        while True:
            rounds += 1
            state.update(best=math.inf, at=done_total, start=done_total)
            # after legs were found in collision: polish only (re-decode around the blocked
            # legs), with kicks every SPARSE_REPAIR_EVERY rounds
            budget = kicks if rounds == 1 else (
                min(kicks, SPARSE_REPAIR_KICKS) if rounds % SPARSE_REPAIR_EVERY == 0 else 0)

            def on_chunk(done: int, best: float, base: int = done_total) -> None:
                if best < state["best"] - 1e-12:
                    state["best"], state["at"] = best, base + done
                    history_gen.append(base + done)
                    history_cost.append(best)
                bar.update(base + done - state["done"])
                state["done"] = base + done
                bar.set_postfix_str(f"best {best:.4f}")

            out = ts.search(problem.sparse, seed=seed + rounds - 1,
                            kicks=budget, tour=tour, choice=choice,
                            should_stop=should_stop, on_chunk=on_chunk)
            done_total += out.kicks
            tour, choice = out.tour, out.choice
            flat_tour = [-1 if t == n else int(problem.offsets[t] + choice[t]) for t in tour]
            missing = [(int(a), int(b)) for a, b in zip(tour[1:-2], tour[2:-1], strict=True)
                       if not np.any(problem.sparse.nbr[a] == b)]
            if missing:  # the legs the search asked for: add them and search on
                _add_pairs(problem, missing)
                continue
            repair = False
            if problem.checker is not None:
                tc = time.process_time()
                for a, b in zip(flat_tour[:-1], flat_tour[1:], strict=True):
                    key = (min(a, b), max(a, b))
                    if key not in checked_legs:
                        q_lo = problem.home if key[0] < 0 else problem.flat[key[0]]
                        q_hi = problem.flat[key[1]]
                        checked_legs[key] = problem.checker.leg_in_collision(
                            q_lo, q_hi, problem.clearance)
                        if checked_legs[key]:
                            cost = problem.penalty  # forbidden, unless planned around
                            if problem.detours and plans < detour_params.max_plans:
                                plans += 1
                                tp = time.process_time()
                                found = plan_detour(problem.checker, q_lo, q_hi,
                                                    clearance=problem.clearance,
                                                    limits=problem.limits,
                                                    jerk=problem.arm.limits.jerk, seed=seed,
                                                    params=detour_params, attempts=1)
                                cpu["planner"] += time.process_time() - tp
                                tc += time.process_time() - tp
                                if found is not None:
                                    detours[key] = found
                                    cost = found.planned_time
                            problem.mark_leg(a, b, cost)
                            repair = True
                cpu["collision"] += time.process_time() - tc
            if not repair:
                break
            if rounds >= MAX_ROUNDS:
                raise NoPathError(f"legs in collision still in the best tour after {rounds} "
                                  "searches")
    t1 = time.process_time()
    cpu["search"] += t1 - t0 - compiled[0]
    if out.cost >= problem.penalty:
        raise NoPathError(f"no tour avoids the legs in collision ({sum(checked_legs.values())} "
                          f"legs of {len(checked_legs)} checked collide)")
    order = tour[1:-1].astype(np.int64)
    index = choice.astype(np.int64)
    with _compile_apart(cpu) as compiled:
        tb = time.process_time()
        edges, weights, rho, home_min = problem.bound_inputs
        bound = ts.one_tree_bound(n, edges, weights, rho, home_min, upper=out.cost)
        cpu["bound"] += time.process_time() - tb
    cpu["bound"] -= compiled[0]
    chosen, _path, planned, executed = _tour_legs(problem, order, index, False)
    nodes = [-1] + [int(problem.offsets[t] + index[t]) for t in order] + [-1]
    _refine_detours(problem, nodes, detours, detour_params, seed, cpu)
    waypoints = _detour_legs(nodes, detours, planned, executed)
    counts = {
        "targets": n,
        "configurations_per_target": [int(k) for k in problem.counts],
        "configurations": int(problem.offsets[-1]),
        "dropped_in_collision": problem.dropped_in_collision,
        "dropped_dominated": problem.dropped_dominated,
        "dropped_by_cap": problem.dropped_by_cap,
        "candidate_legs": int(problem.sparse.legs.size),
        "legs_checked": len(checked_legs),
        "legs_infeasible": int(sum(checked_legs.values())),
        "legs_planned": plans,
        "legs_plan_found": len(detours),
        "legs_detoured": len(waypoints),
        "detours": problem.detours,
        "plan_budget": detour_params.max_plans if problem.detours else 0,
        "search_rounds": rounds,
        "ga_rounds": 0,
        "kicks": done_total,
    }
    report = SerialReport(order=order, configuration_index=index, configurations=chosen,
                          home=np.array(problem.home), leg_times=executed,
                          planned_leg_times=planned, total_time=float(executed.sum()),
                          collision_checked=problem.checker is not None, counts=counts,
                          cpu=cpu, generations=done_total, restarts=0, seed=seed,
                          open_path=False, problem=problem, detours=waypoints)
    best = np.array(history_cost) if history_cost else np.array([out.cost])
    history = History(float(best[0]), best, best.copy())
    return Result(order=order, total_time=float(executed.sum()), leg_times=executed,
                  matrix=np.zeros((0, 0)), generations=done_total, restarts=0,
                  runtime_s=time.monotonic() - started, seed=seed, history=history,
                  preset=params.preset, lower_bound=bound, certified=None, report=report,
                  constraints=cons, start=None, runs=1, configurations=chosen, cpu=cpu)


@dataclass(frozen=True)
class _Shape:
    """A serial tour's shape in canonical form: nodes 0..N-1 the targets, N the home."""

    constraints: TourConstraints
    canon: Canonical
    closeness: np.ndarray  # (N + 1, N + 1) cheapest planned leg between targets and home

    @property
    def pinned(self) -> bool:
        return self.canon.needs_pins


def _serial_shape(problem: SerialProblem, constraints: TourConstraints | None) -> _Shape:
    """Validate ``constraints`` for a tour from the problem's home and put them in
    canonical form (a first or last target as precedence pairs, an open path's free
    return to the home)."""
    from subtask_opt.tour.constraints import canonical, checked

    constraints = checked(constraints)
    if constraints.home is not None:
        raise ParameterError("a serial arm's tour starts at its home configuration: give it "
                             "as ArmProblem(home=...) (--home q1,...,qn), not as "
                             "TourConstraints.home")
    n = problem.size
    constraints.check_size(n, matrix_home=True, own_home=True)
    pairs = list(constraints.precedence)
    others = range(n)
    if constraints.start is not None:
        pairs += [(constraints.start, j) for j in others if j != constraints.start]
    end = constraints.end
    if end is not None and constraints.tour == "closed":
        pairs += [(j, end) for j in others if j != end]
        end = None
    closeness = np.zeros((n + 1, n + 1))
    closeness[:n, :n] = problem.dist
    closeness[n, :n] = closeness[:n, n] = np.minimum.reduceat(problem.home_out,
                                                              problem.offsets[:-1])
    # the home is node N, where the canonical tour starts (a closed tour returns there,
    # an open path's return is free)
    canon_cons = TourConstraints(tour=constraints.tour, start=n, end=end,
                                 precedence=tuple(dict.fromkeys(pairs)))
    canon = canonical(closeness, canon_cons, default_start=n)
    return _Shape(constraints, canon, closeness)


MAX_KICKS = 1000
"""Most kicks :func:`solve_serial_problem` accepts."""
SERIAL_KICKS = 100
"""Kicks per child of a serial arm's micro-GA from
:data:`~subtask_opt.tour.permutation.KICKS_FROM` targets (the TSP default there is N/10,
at most 100), with :data:`SERIAL_STALL_SHARE` of the default stall. On RoboTSP's 245 holes
(seeds 0-7, the legs checked inside the GA): N/10 = 24 kicks and the whole stall (24) gave
tours of median 63.34 s, mean 63.32 s, in a median 1.7 s of search CPU; 100 kicks and half
the stall (12) 63.15 s, 63.25 s in 0.9 s; two thirds (16) 63.15 s, 63.20 s in 1.2 s; 20
generations 63.12 s, 63.12 s in 1.7 s. (Checking the answers after each search and
searching again, as before, 24 kicks and 24 gave 63.24 s, 63.26 s in 2.9 s.) Half keeps
the search within a second or two at the old tours' length; a longer stall buys 0.1-0.2%."""
SERIAL_STALL_SHARE = 0.5
"""Share of :meth:`~subtask_opt.tour.solve.SolverParams.default_stop`'s stall a serial
arm's micro-GA keeps from :data:`~subtask_opt.tour.permutation.KICKS_FROM` targets, whose
children carry :data:`SERIAL_KICKS` kicks."""


def _serial_search_defaults(params: SolverParams, n: int,
                            kicks: int | None) -> tuple[list[Any], int | None]:
    """The default stop and the kicks of a serial arm's micro-GA for ``n`` targets
    (``kicks`` as given, else :data:`SERIAL_KICKS` from ``KICKS_FROM`` targets)."""
    from subtask_opt.base.stop import NoImprovement
    from subtask_opt.tour.permutation import KICKS_FROM

    stop = params.default_stop(n)
    if n < KICKS_FROM or params.preset == "paper":
        return stop, kicks
    stop = [NoImprovement(max(1, round(c.generations * SERIAL_STALL_SHARE)))
            if isinstance(c, NoImprovement) else c for c in stop]
    return stop, SERIAL_KICKS if kicks is None else kicks


def _search(problem: SerialProblem, seed: int, stop: Any, params: SolverParams,
            kicks: int | None, blocked: dict[tuple[int, int], float], shape: _Shape,
            progress: bool, certify: bool, certify_time_limit: float) -> Result:
    """:func:`solve_serial_problem`'s rounds; every leg it blocks in the problem's leg memory goes
    into ``blocked`` with its time first."""
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.base.results import History
    from subtask_opt.base.stop import MaxGenerations, NoImprovement, TargetCost
    from subtask_opt.ga.config import GAConfig
    from subtask_opt.ga.kinds import Kind
    from subtask_opt.ga.loop import run_ga
    from subtask_opt.tour.permutation import (
        SEARCH_EXACT,
        SEARCH_FAST,
        SEARCH_PAPER,
        make_aux,
        neighbour_table,
    )
    from subtask_opt.tour.pinned_clustered import make_data, make_pinned_clustered_aux
    from subtask_opt.tour.problem import MatrixProblem
    from subtask_opt.tour.solve import PINNED_STALL, _relaxation_bound, _rotate

    n = problem.size
    from subtask_opt.cell.detour import DetourParams, plan_detour

    cpu = dict(problem.cpu)
    cpu["search"] = 0.0
    cpu["planner"] = 0.0
    penalty = problem.penalty
    search = SEARCH_PAPER if params.preset == "paper" else SEARCH_FAST
    config = GAConfig(population=params.population, elite=1, crossover_rate=1.0,
                      mutation_rate=0.0, restart_on_convergence=True,
                      convergence_tol=params.convergence_tol)
    off = problem.offsets
    checked: dict[tuple[int, int], bool] = {}  # (from, to) flat index, -1 = home -> collides
    detours: dict[tuple[int, int], Detour] = {}  # legs in collision planned around (lo -> hi)
    detour_params = problem.detour if problem.detour is not None else DetourParams()
    planner = {"plans": 0}
    generations = restarts = 0
    rounds = ga_rounds = repairs = 0
    t0 = time.process_time()
    canon = shape.canon
    open_path = canon.open_path
    # the legs are symmetric, so a closed tour's search uses neighbour lists over targets +
    # home; an open path's free return to the home is not, so it searches exactly
    home_in = problem.home_in
    if open_path:
        home_in = np.zeros_like(problem.home_in)
        search = SEARCH_PAPER if params.preset == "paper" else SEARCH_EXACT
    data = _gc.ConfiguredData(problem.dist.copy(), off, problem._legs_memory,
                              problem.home_out.copy(), home_in.copy(), float(search),
                              (np.zeros((0, 0), dtype=np.int64) if open_path
                               else _near(problem, params.neighbours)),
                              np.zeros((0, 0)) if open_path else problem._cheapest)
    bound = None
    if n + 1 <= params.bound_max_nodes:
        # every leg costs at least its targets' cheapest one, so a bound of the target
        # matrix bounds every tour (and a tour that meets it is optimal)
        bound = _relaxation_bound(MatrixProblem(shape.closeness), canon, canon.matrix)
    history = History(math.inf, np.zeros(0), np.zeros(0))
    runtime = 0.0
    runs = 0
    owner = np.repeat(np.arange(n), np.diff(off))
    genes = np.zeros(n, dtype=np.int64)
    aux = None
    repair = False  # True: the last round blocked legs of the current order
    again = False  # True: search once more knowing the legs found in collision
    best: tuple[float, np.ndarray, np.ndarray] | None = None  # best collision-free answer
    pinned_dist: list[np.ndarray] = []  # the pinned kind's target costs, kept like data.dist
    plain_rounds = 0  # GA rounds that did not check legs as they went

    def check_legs(tour: list[int]) -> bool:
        """Check the legs of ``tour`` (flat configurations, -1 = home) not checked before;
        one in collision costs its planned detour (within the budget) or the penalty from
        now on (in ``data``, in place). Returns whether any was in collision."""
        if problem.checker is None:
            return False
        found = False
        t0 = time.process_time()
        spent = 0.0  # CPU of the planner inside this loop (not collision checking)
        for a, b in zip(tour[:-1], tour[1:], strict=True):
            key = (min(a, b), max(a, b))
            if key in checked:
                continue  # verified before: its cost (straight, detour or penalty) is exact
            q_lo = problem.home if key[0] < 0 else problem.flat[key[0]]
            q_hi = problem.flat[key[1]]
            checked[key] = problem.checker.leg_in_collision(q_lo, q_hi, problem.clearance)
            if not checked[key]:
                continue
            found = True
            cost = penalty
            if problem.detours and planner["plans"] < detour_params.max_plans:
                planner["plans"] += 1
                t1 = time.process_time()
                detour = plan_detour(problem.checker, q_lo, q_hi, clearance=problem.clearance,
                                     limits=problem.limits, jerk=problem.arm.limits.jerk,
                                     seed=seed, params=detour_params, attempts=1)
                spent += time.process_time() - t1
                if detour is not None:
                    detours[key] = detour
                    cost = detour.planned_time
            if key[0] < 0:
                data.home_out[key[1]] = cost
                if not open_path:  # an open path's return to the home is free
                    data.home_in[key[1]] = cost
            else:
                blocked.setdefault(key, float(data.legs[key]))
                data.legs[a, b] = data.legs[b, a] = cost
                ta, tb = owner[a], owner[b]
                block = data.legs[off[ta]:off[ta + 1], off[tb]:off[tb + 1]]
                data.dist[ta, tb] = data.dist[tb, ta] = block.min()
                for costs in pinned_dist:
                    costs[ta, tb] = costs[tb, ta] = data.dist[ta, tb]
        cpu["collision"] += time.process_time() - t0 - spent
        cpu["planner"] += spent
        return found

    in_ga = [0.0]  # CPU of the checks inside a GA round (not search time)

    def check_best(chromosome: np.ndarray) -> bool:
        """The GA's lazy leg check (``run_ga``'s ``on_best``) of a new best chromosome."""
        t0 = time.process_time()
        with compile_seconds() as compiled:  # counted apart already
            order = (_rotate(chromosome, n)[1:] if shape.pinned
                     else chromosome).astype(np.int64)
            choice = np.zeros(n, dtype=np.int64)
            _gc.decode(order, n, data, choice)
            found = check_legs([-1] + [int(off[g] + choice[g]) for g in order]
                               + ([] if open_path else [-1]))
        spent = time.process_time() - t0
        in_ga[0] += spent - min(compiled[0], spent)
        if problem.detours and planner["plans"] > detour_params.max_plans * CLUTTERED_SHARE:
            raise _Cluttered
        return found

    def forget_checks() -> None:
        """Every leg back to its straight time, as before any check."""
        for (a, b), value in blocked.items():
            data.legs[a, b] = data.legs[b, a] = value
        blocked.clear()
        data.dist[:] = problem.dist
        data.home_out[:] = problem.home_out
        data.home_in[:] = home_in
        checked.clear()
        detours.clear()
        planner["plans"] = 0

    on_best = check_best if problem.checker is not None else None
    cpu["search"] += time.process_time() - t0
    while True:
        rounds += 1
        t0 = time.process_time()
        choice = np.zeros(n, dtype=np.int64)
        cost = math.inf
        if n == 1 or (repair and repairs < MAX_REPAIRS):
            repairs += 1
            if aux is not None and not shape.pinned:  # the pinned order is kept as it is
                _gc.local_search(genes, n, data, aux)
            cost = float(_gc.decode(genes, n, data, choice))
        if cost >= penalty and n > 1:  # the first or last search, or a repair that failed
            if best is not None and (not again or ga_rounds >= MAX_ROUNDS):
                break  # the collision-free answer found so far stands
            if ga_rounds >= MAX_ROUNDS:
                raise NoPathError(f"legs in collision still in the best tour after "
                                  f"{ga_rounds} searches")
            repairs = 0
            again = False
            default_stop, round_kicks = _serial_search_defaults(params, n, kicks)
            aux = make_aux(neighbour_table(data.dist, params.neighbours),
                           nearest_fallback=params.preset != "paper",
                           grasp_share=params.grasp_share, max_segment=params.max_segment,
                           neighbours=params.neighbours, search=search, kicks=round_kicks)
            criteria = as_criteria(stop, default_stop)
            if shape.pinned and stop is None and params.preset != "paper":
                criteria = [NoImprovement(max(PINNED_STALL, n // 2)), MaxGenerations(50_000)]
            if bound is not None and stop is None and ga_rounds == 0:
                criteria = [*criteria, TargetCost(bound * (1 + 1e-12) + 1e-12)]
            ga_rounds += 1
            plain_rounds += on_best is None
            in_ga[0] = 0.0
            total = next((c.generations for c in criteria if isinstance(c, MaxGenerations)),
                         None)
            with _compile_apart(cpu) as compiled, progress_bar(
                    progress, total=total, desc=f"micro-GA round {ga_rounds}",
                    unit="gen") as bar:
                on_chunk = _reporter(bar)
                try:
                    if shape.pinned:  # the order and the configurations together, pairs kept
                        costs = np.array(canon.matrix)
                        costs[:n, :n] = data.dist
                        pinned = make_pinned_clustered_aux(n + 1, canon.first, canon.last,
                                                           canon.pairs)
                        pinned_data = make_data(costs, data, home=n)
                        pinned_dist[:] = [pinned_data.dist]
                        outcome = run_ga(use(Kind.PINNED_CLUSTERED), config, pinned_data,
                                         pinned, max_genes=n + 1, seed=seed,
                                         criteria=criteria, on_chunk=on_chunk,
                                         runs=params.runs or 1, on_best=on_best)
                        genes = _rotate(outcome.genes, n)[1:].astype(np.int64)
                    else:
                        outcome = run_ga(use(Kind.CONFIGURED_PERMUTATION), config, data, aux,
                                         max_genes=n, seed=seed, criteria=criteria,
                                         on_chunk=on_chunk, runs=params.runs or 1,
                                         on_best=on_best)
                        genes = outcome.genes.astype(np.int64)
                except _Cluttered:
                    outcome = None
            t0 += compiled[0] + in_ga[0]  # not search time
            if outcome is None:
                # so cluttered a cell that the new bests' legs take much of the plan budget:
                # it is better spent on whole answers' legs, so start again checking those
                # after each search (repairs, then a second search knowing them)
                forget_checks()
                on_best = None
                ga_rounds -= 1
                cpu["search"] += time.process_time() - t0
                continue
            generations += outcome.generations
            restarts += outcome.restarts
            runtime += outcome.runtime_s
            runs = outcome.runs  # per search (every round makes as many)
            if ga_rounds == 1:
                history = outcome.history
            cost = float(_gc.decode(genes, n, data, choice))
        cpu["search"] += time.process_time() - t0
        tour = [-1] + [int(off[g] + choice[g]) for g in genes] + ([] if open_path else [-1])
        if cost >= penalty and best is not None:
            break  # a later search found nothing better than the collision-free answer
        if cost >= penalty:
            raise NoPathError(
                f"no tour avoids the legs in collision ({sum(checked.values())} legs of "
                f"{len(checked)} checked collide); try a larger axis step sampling, another "
                "home or fewer obstacles")
        repair = check_legs(tour)  # a cost of this tour was corrected: decode it again
        if not repair:
            if best is None or cost < best[0]:
                best = (cost, genes.copy(), choice.copy())
            if on_best is None and plain_rounds == 1 and any(checked.values()):
                again = True
                continue
            break
    assert best is not None  # the loop ends only after recording a collision-free answer
    _, order, index = best
    broken = canon.violations(np.concatenate([[n], order]))
    if broken:  # the operators keep every constraint: this is a bug, never an answer
        raise SubtaskOptError(f"internal error: the answer breaks its constraints: {broken}")
    chosen, path, planned, executed = _tour_legs(problem, order, index, open_path)
    nodes = [-1] + [int(off[t] + index[t]) for t in order] + ([] if open_path else [-1])
    _refine_detours(problem, nodes, detours, detour_params, seed, cpu)
    waypoints = _detour_legs(nodes, detours, planned, executed)
    counts = {
        "targets": n,
        "configurations_per_target": [int(k) for k in problem.counts],
        "configurations": int(problem.offsets[-1]),
        "dropped_in_collision": problem.dropped_in_collision,
        "legs_checked": len(checked),
        "legs_infeasible": int(sum(checked.values())),
        "legs_planned": planner["plans"],
        "legs_plan_found": len(detours),
        "legs_detoured": len(waypoints),
        "detours": problem.detours,
        "plan_budget": detour_params.max_plans if problem.detours else 0,
        "search_rounds": rounds,
        "ga_rounds": ga_rounds,
    }
    certified = None
    if certify:
        t0 = time.process_time()
        certified = _certify_serial(problem, data, shape, order, index, float(planned.sum()),
                                    certify_time_limit)
        cpu["certify"] = time.process_time() - t0
    report = SerialReport(order=order, configuration_index=index, configurations=chosen,
                          home=np.array(problem.home), leg_times=executed,
                          planned_leg_times=planned, total_time=float(executed.sum()),
                          collision_checked=problem.checker is not None, counts=counts,
                          cpu=cpu, generations=generations, restarts=restarts, seed=seed,
                          open_path=open_path, problem=problem, detours=waypoints)
    return Result(order=order, total_time=float(executed.sum()), leg_times=executed,
                  matrix=np.zeros((0, 0)), generations=generations, restarts=restarts,
                  runtime_s=runtime, seed=seed, history=history, preset=params.preset,
                  lower_bound=bound, certified=certified, report=report,
                  constraints=shape.constraints, start=None, runs=max(runs, 1),
                  configurations=chosen, cpu=cpu)


def _certify_serial(problem: SerialProblem, data: Any, shape: _Shape, order: np.ndarray,
                    index: np.ndarray, planned: float, time_limit: float) -> str:
    """Prove the planned time optimal over every order and configuration, or say why not.

    Up to :data:`~subtask_opt.tour.exact.CLUSTERED_HELD_KARP_MAX` targets, any shape:
    Held and Karp's programme over (targets visited, configuration last visited),
    precedence and a fixed first or last target kept. Larger closed tours without
    precedence: the generalised-TSP branch and cut
    (:func:`~subtask_opt.tour.exact.gtsp_optimum`, the home a cluster of one node).
    Legs found in collision count as impossible (no feasible tour uses one)."""
    from subtask_opt.tour.exact import CLUSTERED_HELD_KARP_MAX, clustered_held_karp, gtsp_optimum

    canon = shape.canon
    n = problem.size
    m = int(problem.offsets[-1])
    try:
        if n <= CLUSTERED_HELD_KARP_MAX:
            pairs = canon.pairs[(canon.pairs < n).all(axis=1)]
            optimum = clustered_held_karp(
                data.legs, problem.offsets, data.home_out,
                None if canon.open_path else data.home_in, pairs=pairs,
                last=canon.last if canon.last < n else -1)
        elif canon.open_path or shape.pinned:
            return (f"not certified: {n} targets; open paths, precedence and fixed first or "
                    f"last targets are certified up to {CLUSTERED_HELD_KARP_MAX} targets")
        elif m > MAX_CERTIFY_NODES:
            return (f"not certified: {m} configurations; the branch and cut takes at most "
                    f"{MAX_CERTIFY_NODES}")
        else:
            cost = np.zeros((m + 1, m + 1))
            cost[:m, :m] = data.legs
            cost[m, :m] = cost[:m, m] = data.home_out
            owner = np.repeat(np.arange(n + 1), np.append(problem.counts, 1))
            incumbent = [m] + [int(problem.offsets[t] + index[t]) for t in order]
            optimum = gtsp_optimum(cost, owner, incumbent=incumbent,
                                   time_limit=time_limit)[0]
    except SubtaskOptError as exc:
        return f"not certified: {exc}"
    if planned <= optimum * (1 + 1e-9) + 1e-12:
        return "optimal (proven, planned times)"
    return (f"not optimal: the proven optimum of the planned times is {optimum:.6g} "
            f"({100 * (planned / optimum - 1):.4f}% less)")


MAX_CERTIFY_NODES = 3000
"""Most configurations :func:`solve_serial_problem` hands its certificate's branch and cut."""


def _reporter(bar: Any) -> Callable[[Progress], None]:
    """A GA chunk callback that moves ``bar`` to the generation reached."""
    done = [0]

    def on_chunk(p: Progress) -> None:
        bar.update(p.generation - done[0])
        done[0] = p.generation
        bar.set_postfix_str(f"best {p.best_cost:.4f}")
    return on_chunk


def _near(problem: SerialProblem, k: int) -> np.ndarray:
    """(N + 1, k) nearest nodes of each target and home (node N) by their cheapest legs."""
    from subtask_opt.tour.permutation import neighbour_table

    n = problem.size
    off = problem.offsets
    closeness = np.zeros((n + 1, n + 1))
    closeness[:n, :n] = problem.dist
    closeness[n, :n] = closeness[:n, n] = np.minimum.reduceat(problem.home_out, off[:-1])
    return neighbour_table(closeness, k)


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
