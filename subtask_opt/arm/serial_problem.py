"""Sequencing pose targets for any serial arm: order and configuration together.

A :class:`SerialProblem` is built once: every IK solution of every target
(configurations in collision with the scene or the arm itself dropped), then
the matrix of joint-space leg times between all configurations and the home
configuration (the synchronised per-joint trapezoid,
:func:`~subtask_opt.arm.timing.joint_legs.trapezoid_leg_times`).
:func:`solve_serial` searches the order and one configuration per target
together (a generalised TSP on the shared micro-GA core, decoded exactly by a
layered shortest path, :mod:`subtask_opt.arm._configuration_kernels`), tour
home -> targets -> home.

Legs are checked for collisions lazily: after a search, every leg of the
answer is swept (:meth:`~subtask_opt.arm.scene.CollisionChecker.leg_in_collision`
with the problem's clearance); a leg in collision is marked *infeasible* (a
large finite penalty, so the GA avoids it) and the same order is decoded again
and polished, until the answer uses only collision-free legs; then the GA runs
once more knowing those legs and the shorter answer is kept
(:func:`solve_serial`). Detours through via configurations are not attempted
(``legs_detoured`` is always 0).

The result's ``leg_times`` and ``total_time`` are the *executed* times:
ruckig's time-optimal synchronised profiles with the arm's jerk limits for
the chosen legs (equal to the trapezoid times when the arm has none).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt._kernel_cache import compile_seconds
from subtask_opt.arm import _configuration_kernels as _gc
from subtask_opt.arm.timing.joint_legs import (
    JointLimits,
    joint_limits,
    ruckig_leg_time,
    trapezoid_leg_times,
    trapezoid_square,
)
from subtask_opt.base.errors import (
    InputDataError,
    NoPathError,
    ParameterError,
    require_in_range,
    require_int,
)
from subtask_opt.base.stop import StoppingCriterion, as_criteria

if TYPE_CHECKING:
    from subtask_opt.arm.ik import IKParams
    from subtask_opt.arm.poses import PoseTargets
    from subtask_opt.arm.scene import CollisionChecker, Scene
    from subtask_opt.arm.sequencing import SolverParams
    from subtask_opt.arm.serial import SerialArm

MAX_CONFIGURATIONS = 20_000
"""Most configurations (over all targets) a problem may hold: the leg matrix is M x M."""


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
        arm: the arm (:func:`subtask_opt.arm.serial.load_serial_arm`), with
            acceleration limits.
        home: (n,) home configuration in radians; the tour starts and ends there.
        scene: boxes to avoid (None: self-collision only).
        ik: IK settings (default: every distinct solution modulo 2 pi, no +-2 pi
            alternatives, which would multiply the configurations).
        clearance: (m) legs are swept so that no point of the arm moves more
            than this between two checked configurations.
        check_collisions: check configurations and legs at all.
        ik_seed: seed of the IK's random starts.

    Built on construction (read-only): ``configurations`` (per target, (K_i, n)),
    ``offsets``, ``flat`` (M, n), ``legs`` (M, M, symmetric), ``home_out``/``home_in``
    (M,, equal), ``dist`` (N, N) the cheapest leg between each pair of targets,
    ``penalty`` (the finite time that stands for a leg found in collision: more than
    any tour of possible legs), ``cpu`` (seconds of IK, collision and matrix work, and
    numba's compilation apart) and the collision checker.

    Raises:
        ParameterError: bad home shape, clearance, or too many configurations.
        InputDataError: home outside the limits or in collision; a target with no
            (collision-free) configuration, naming its row.
    """

    targets: PoseTargets
    arm: SerialArm
    home: Any
    scene: Scene | None = None
    ik: IKParams | None = None
    clearance: float = 0.01
    check_collisions: bool = True
    ik_seed: int = 0
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
    # ``legs`` is a read-only view of this array; solve_serial hands it to the kernels
    # without an M x M copy (a read-only array would be compiled for separately), blocks
    # the legs it finds in collision in place and restores them before it returns, under
    # ``_lock``
    _legs_memory: np.ndarray = field(init=False, repr=False)
    # cheapest leg between each target and each configuration (ConfiguredData.cheapest),
    # writable like ``_legs_memory`` for the same reason
    _cheapest: np.ndarray = field(init=False, repr=False)
    _lock: threading.Lock = field(init=False, repr=False, default_factory=threading.Lock)

    def __post_init__(self) -> None:
        from subtask_opt.arm.ik import IKParams, IKSolver
        from subtask_opt.arm.poses import PoseTargets
        from subtask_opt.arm.serial import SerialArm

        if not isinstance(self.targets, PoseTargets):
            raise ParameterError(f"SerialProblem.targets must be PoseTargets, got "
                                 f"{type(self.targets).__name__}")
        if not isinstance(self.arm, SerialArm):
            raise ParameterError(f"SerialProblem.arm must be a SerialArm, got "
                                 f"{type(self.arm).__name__}")
        require_in_range("SerialProblem", "clearance", self.clearance, 1e-4, 1.0)
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
        object.__setattr__(self, "limits", joint_limits(arm.limits.velocity, acc))
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

        with _phase(cpu, "ik"):
            params = self.ik if self.ik is not None else IKParams(wrap_alternatives=False)
            solutions = IKSolver(arm, params).solve_targets(self.targets, seed=self.ik_seed)
        configs = []
        dropped = 0
        for i, q in enumerate(solutions.configurations):
            point = np.round(self.targets.points[i], 6).tolist()
            if q.shape[0] == 0:
                raise InputDataError(f"target {i} (row {i + 1}, point {point}) has no IK "
                                     f"solution within the joint limits of {arm.name}")
            if checker is not None:
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
        counts = np.array([q.shape[0] for q in configs], dtype=np.int64)
        if counts.sum() > MAX_CONFIGURATIONS:
            raise ParameterError(
                f"{counts.sum()} configurations in all, more than {MAX_CONFIGURATIONS}: use a "
                "coarser axis step or fewer targets")
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        flat = np.ascontiguousarray(np.vstack(configs))
        with _phase(cpu, "matrix"):
            memory = trapezoid_square(flat, self.limits)
            legs = memory.view()
            home_out = trapezoid_leg_times(home, flat, self.limits)[0]
            home_in = home_out.copy()  # the trapezoid time is the same either way
            dist, cheapest, top = _gc.block_minima(memory, offsets)
        penalty = (len(configs) + 2) * max(float(top), float(home_out.max())) + 1.0
        for name, value in (("configurations", tuple(configs)), ("offsets", offsets),
                            ("flat", flat), ("legs", legs), ("dist", dist),
                            ("penalty", penalty), ("home_out", home_out),
                            ("home_in", home_in), ("cpu", cpu), ("_cheapest", cheapest),
                            ("dropped_in_collision", dropped), ("_legs_memory", memory)):
            if isinstance(value, np.ndarray) and value is not memory and value is not cheapest:
                value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def size(self) -> int:
        """Number of targets."""
        return len(self.configurations)

    @property
    def counts(self) -> np.ndarray:
        """(N,) configurations per target."""
        return np.diff(self.offsets)


def _self_checker(arm: SerialArm) -> CollisionChecker:
    from subtask_opt.arm.scene import CollisionChecker

    return CollisionChecker(arm)


@dataclass(frozen=True, eq=False)
class SerialResult:
    """The answer of :func:`solve_serial`.

    Attributes:
        order: (N,) target indices in visiting order (home before the first, after the last).
        configuration_index: (N,) per target (input order), the index of its chosen
            configuration among ``problem.configurations[i]``.
        configurations: (N, n) the chosen joint vector of each target, input order.
        home: (n,) home configuration (radians).
        leg_times: (N + 1,) executed (ruckig) time of each leg: home -> order[0], ...,
            order[-1] -> home.
        planned_leg_times: (N + 1,) the same legs' trapezoid times (the search's model).
        total_time: sum of ``leg_times`` (s).
        collision_checked: whether configurations and the tour's legs were checked.
        counts: targets, configurations per target, legs checked, legs infeasible,
            legs detoured, configurations dropped in collision, search rounds (of the
            lazy leg check) and how many of them ran the GA.
        cpu: CPU seconds of IK, collision checks, matrix, search, and apart from them
            numba's compilation (or loading compiled code) on a first run.
        generations, restarts: what the micro-GA did (summed over rounds).
        seed: the seed.
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

    @property
    def planned_time(self) -> float:
        """Sum of the trapezoid times of the tour's legs (s)."""
        return float(self.planned_leg_times.sum())

    def tour_configurations(self) -> np.ndarray:
        """(N + 2, n) joint vectors in tour order: home, targets, home."""
        return np.vstack([self.home, self.configurations[self.order], self.home])

    def summary(self) -> str:
        """A few lines for a terminal."""
        c = self.counts
        cpu = ", ".join(f"{k} {v:.3f} s" for k, v in self.cpu.items())
        return "\n".join([
            f"{c['targets']} targets, {sum(c['configurations_per_target'])} configurations "
            f"({min(c['configurations_per_target'])}-{max(c['configurations_per_target'])} "
            f"per target), seed {self.seed}",
            f"total time {self.total_time:.4f} s executed (ruckig), "
            f"{self.planned_time:.4f} s planned (trapezoid)",
            f"legs checked {c['legs_checked']}, infeasible {c['legs_infeasible']}, "
            f"detoured {c['legs_detoured']}" + ("" if self.collision_checked
                                                 else " (collisions not checked)"),
            f"CPU: {cpu}",
            "order: " + " ".join(str(int(i)) for i in self.order),
        ])

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (the CLI's ``--json``); joint values in radians."""
        return {
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
            "units": {"time": "s", "joints": "rad"},
        }


MAX_ROUNDS = 200
"""Most GA searches of the lazy leg check before :func:`solve_serial` gives up."""
MAX_REPAIRS = 100
"""Most repair rounds in a row before :func:`solve_serial` runs the GA again."""


def solve_serial(problem: SerialProblem, *, seed: int = 0,
                 stop: StoppingCriterion | list[StoppingCriterion] | None = None,
                 params: SolverParams | None = None, kicks: int | None = None) -> SerialResult:
    """Order the targets and pick one configuration each for minimum time, home to home.

    The first round runs the micro-GA (``stop``; default ``params.default_stop(n)``;
    ``params.runs`` independent runs, default one).
    When the answer uses a leg found in collision, that leg is blocked and the same order
    is decoded again and polished by the local search (a repair round: the blocked leg
    is usually replaced by another configuration of one of its targets), until a tour
    uses no leg found in collision. The GA then runs once more from scratch, knowing
    every leg found so far, and the shorter collision-free answer is kept (repairing
    alone is quicker but usually ends a little longer: benchmarks/robotsp.py). The GA
    also runs again when a repair cannot avoid the blocked legs, or after
    :data:`MAX_REPAIRS` repairs in a row.

    The legs found in collision are blocked in the problem's leg matrix during the call
    (an M x M copy would cost as much as the search) and restored before it returns;
    concurrent calls on one problem wait for each other.

    Args:
        kicks: kicks of the iterated local search per child and restart individual
            (:func:`subtask_opt.ga.permutation.make_aux`); None: its default for N targets.

    Raises:
        ParameterError: a bad seed, params or kicks.
        NoPathError: no tour avoids the legs found in collision.
    """
    from subtask_opt.arm.sequencing import SolverParams

    if not isinstance(problem, SerialProblem):
        raise ParameterError(f"solve_serial needs a SerialProblem, got {type(problem).__name__}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not (
            0 <= seed < 2**63):
        raise ParameterError(f"seed must be an integer in [0, 2**63), got {seed!r}")
    params = params if params is not None else SolverParams()
    if not isinstance(params, SolverParams):
        raise ParameterError(f"solve_serial: params must be a SolverParams, got {params!r}")
    if kicks is not None:
        require_int("solve_serial", "kicks", kicks, 0, MAX_KICKS)
    with problem._lock:
        blocked: dict[tuple[int, int], float] = {}  # leg (a, b), a < b -> its time
        try:
            return _search(problem, int(seed), stop, params, kicks, blocked)
        finally:
            memory = problem._legs_memory
            for (a, b), value in blocked.items():
                memory[a, b] = memory[b, a] = value


MAX_KICKS = 1000
"""Most kicks :func:`solve_serial` accepts."""


def _search(problem: SerialProblem, seed: int, stop: Any, params: SolverParams,
            kicks: int | None, blocked: dict[tuple[int, int], float]) -> SerialResult:
    """:func:`solve_serial`'s rounds; every leg it blocks in the problem's leg memory goes
    into ``blocked`` with its time first."""
    from subtask_opt.ga.config import GAConfig
    from subtask_opt.ga.kinds import Kind
    from subtask_opt.ga.loop import run_ga
    from subtask_opt.ga.permutation import SEARCH_FAST, SEARCH_PAPER, make_aux, neighbour_table

    n = problem.size
    cpu = dict(problem.cpu)
    cpu["search"] = 0.0
    penalty = problem.penalty
    search = SEARCH_PAPER if params.preset == "paper" else SEARCH_FAST
    config = GAConfig(population=params.population, elite=1, crossover_rate=1.0,
                      mutation_rate=0.0, restart_on_convergence=True,
                      convergence_tol=params.convergence_tol)
    off = problem.offsets
    checked: dict[tuple[int, int], bool] = {}  # (from, to) flat index, -1 = home -> collides
    generations = restarts = 0
    rounds = ga_rounds = repairs = 0
    t0 = time.process_time()
    # the legs are symmetric, so the search uses neighbour lists over targets + home
    data = _gc.ConfiguredData(problem.dist.copy(), off, problem._legs_memory,
                              problem.home_out.copy(), problem.home_in.copy(), float(search),
                              _near(problem, params.neighbours), problem._cheapest)
    owner = np.repeat(np.arange(n), np.diff(off))
    genes = np.zeros(n, dtype=np.int64)
    aux = None
    repair = False  # True: the last round blocked legs of the current order
    again = False  # True: search once more knowing the legs found in collision
    best: tuple[float, np.ndarray, np.ndarray] | None = None  # best collision-free answer
    cpu["search"] += time.process_time() - t0
    while True:
        rounds += 1
        t0 = time.process_time()
        choice = np.zeros(n, dtype=np.int64)
        cost = math.inf
        if n == 1 or (repair and repairs < MAX_REPAIRS):
            repairs += 1
            if aux is not None:
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
            aux = make_aux(neighbour_table(data.dist, params.neighbours),
                           nearest_fallback=params.preset != "paper",
                           grasp_share=params.grasp_share, max_segment=params.max_segment,
                           neighbours=params.neighbours, search=search, kicks=kicks)
            criteria = as_criteria(stop, params.default_stop(n))
            ga_rounds += 1
            with _compile_apart(cpu) as compiled:
                outcome = run_ga(Kind.CONFIGURED_PERMUTATION, config, data, aux, max_genes=n,
                                 seed=seed, criteria=criteria, runs=params.runs or 1)
            t0 += compiled[0]  # not search time
            genes = outcome.genes.astype(np.int64)
            generations += outcome.generations
            restarts += outcome.restarts
            cost = float(_gc.decode(genes, n, data, choice))
        cpu["search"] += time.process_time() - t0
        tour = [-1] + [int(off[g] + choice[g]) for g in genes] + [-1]
        if cost >= penalty and best is not None:
            break  # a later search found nothing better than the collision-free answer
        if cost >= penalty:
            raise NoPathError(
                f"no tour avoids the legs in collision ({sum(checked.values())} legs of "
                f"{len(checked)} checked collide); try a larger axis step sampling, another "
                "home or fewer obstacles")
        repair = False
        t0 = time.process_time()
        for a, b in zip(tour[:-1], tour[1:], strict=True):
            if problem.checker is None:
                break
            key = (min(a, b), max(a, b))
            if key not in checked:
                qa = problem.home if a < 0 else problem.flat[a]
                qb = problem.home if b < 0 else problem.flat[b]
                checked[key] = problem.checker.leg_in_collision(qa, qb, problem.clearance)
            if checked[key]:
                repair = True
                if a < 0 or b < 0:
                    data.home_out[max(a, b)] = data.home_in[max(a, b)] = penalty
                else:
                    blocked.setdefault(key, float(data.legs[key]))
                    data.legs[a, b] = data.legs[b, a] = penalty
                    ta, tb = owner[a], owner[b]
                    block = data.legs[off[ta]:off[ta + 1], off[tb]:off[tb + 1]]
                    data.dist[ta, tb] = data.dist[tb, ta] = block.min()
        cpu["collision"] += time.process_time() - t0
        if not repair:
            if best is None or cost < best[0]:
                best = (cost, genes.copy(), choice.copy())
            if ga_rounds == 1 and any(checked.values()):
                again = True
                continue
            break
    assert best is not None  # the loop ends only after recording a collision-free answer
    _, order, index = best
    chosen, path, planned, executed = _tour_legs(problem, order, index)
    counts = {
        "targets": n,
        "configurations_per_target": [int(k) for k in problem.counts],
        "configurations": int(problem.offsets[-1]),
        "dropped_in_collision": problem.dropped_in_collision,
        "legs_checked": len(checked),
        "legs_infeasible": int(sum(checked.values())),
        "legs_detoured": 0,
        "search_rounds": rounds,
        "ga_rounds": ga_rounds,
    }
    return SerialResult(order=order, configuration_index=index, configurations=chosen,
                        home=np.array(problem.home), leg_times=executed,
                        planned_leg_times=planned, total_time=float(executed.sum()),
                        collision_checked=problem.checker is not None, counts=counts,
                        cpu=cpu, generations=generations, restarts=restarts, seed=seed)


def _near(problem: SerialProblem, k: int) -> np.ndarray:
    """(N + 1, k) nearest nodes of each target and home (node N) by their cheapest legs."""
    from subtask_opt.ga.permutation import neighbour_table

    n = problem.size
    off = problem.offsets
    closeness = np.zeros((n + 1, n + 1))
    closeness[:n, :n] = problem.dist
    closeness[n, :n] = closeness[:n, n] = np.minimum.reduceat(problem.home_out, off[:-1])
    return neighbour_table(closeness, k)


def _tour_legs(problem: SerialProblem, order: np.ndarray, choice: np.ndarray) -> tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The chosen configurations (input order), the joint path home -> ... -> home, and each
    leg's planned (trapezoid) and executed (ruckig) time."""
    n = problem.size
    chosen = np.array([problem.configurations[i][choice[i]] for i in range(n)])
    path = np.vstack([problem.home, chosen[order], problem.home])
    planned = np.array([trapezoid_leg_times(path[k], path[k + 1], problem.limits)[0, 0]
                        for k in range(n + 1)])
    lim = problem.arm.limits
    executed = np.array([ruckig_leg_time(path[k], path[k + 1], lim.velocity,
                                         problem.limits.acceleration, lim.jerk)
                         for k in range(n + 1)])
    return chosen, path, planned, executed


def evaluate_tour(problem: SerialProblem, order: Any, choice: Any, *, seed: int = 0,
                  cpu: dict[str, float] | None = None) -> SerialResult:
    """The :class:`SerialResult` of a given tour (another method's answer, say).

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
    return SerialResult(order=o, configuration_index=c, configurations=chosen,
                        home=np.array(problem.home), leg_times=executed,
                        planned_leg_times=planned, total_time=float(executed.sum()),
                        collision_checked=problem.checker is not None, counts=counts,
                        cpu=dict(cpu or {}), generations=0, restarts=0, seed=int(seed))


def default_home(arm: SerialArm) -> np.ndarray | None:
    """The home (radians) the robot's JSON file beside its URDF gives as ``home_deg``, or None."""
    import json

    path = arm.urdf_path.with_suffix(".json")
    if not path.is_file():
        from subtask_opt.arm.serial import robots_dir

        path = robots_dir() / f"{arm.name}.json"
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    home = doc.get("home_deg") if isinstance(doc, dict) else None
    if home is None:
        return None
    return np.radians(np.asarray(home, dtype=np.float64))


def serial_problem_from_files(robot: str, case: str | Path, *, scene: str | Path | None = None,
                              home_deg: Any = None, standoff: float = 0.0,
                              axis_step: float = 45.0, tool_frame: str | None = None,
                              limits: Any = None, clearance: float = 0.01) -> SerialProblem:
    """A :class:`SerialProblem` from a robot name or URDF, a target file and a scene file.

    ``home_deg`` (degrees) defaults to the robot file's ``home_deg``; ``limits`` is a
    limit-set name or a JSON file of per-joint arrays (see
    :func:`~subtask_opt.arm.serial.load_serial_arm`).
    """
    import json

    from subtask_opt.arm.poses import load_targets
    from subtask_opt.arm.scene import Scene
    from subtask_opt.arm.serial import load_serial_arm

    lim: Any = limits
    if isinstance(limits, (str, Path)) and str(limits).lower().endswith(".json"):
        try:
            lim = json.loads(Path(limits).read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise InputDataError(f"cannot read the limits file {limits}: {exc}") from None
    arm = load_serial_arm(robot, tool_frame=tool_frame, limits=lim)
    targets = load_targets(case, axis_step=axis_step, standoff=standoff)
    if home_deg is None:
        home = default_home(arm)
        if home is None:
            raise ParameterError(f"{arm.name} has no default home: give --home q1,...,q{arm.nq} "
                                 "in degrees")
    else:
        home = np.radians(np.asarray(home_deg, dtype=np.float64))
        if home.shape != (arm.nq,):
            raise ParameterError(f"home must have {arm.nq} joint values for {arm.name}, got "
                                 f"{len(home)}")
    box_scene = Scene.load(scene) if scene is not None else None
    return SerialProblem(targets, arm, home, scene=box_scene, clearance=clearance)


__all__ = ["MAX_CONFIGURATIONS", "SerialProblem", "SerialResult", "default_home",
           "evaluate_tour",
           "serial_problem_from_files", "solve_serial"]
