"""A tour from a home through clusters of nodes whose legs are verified lazily.

A :class:`LazyLegsProblem` is the robot-free core of a serial arm's sequencing: N targets
(clusters), each owning some nodes (an arm's configurations), a home node the tour starts
and ends at (an open path: starts at), and the time of every leg between two nodes and
between the home and each node. The leg times are *optimistic*: a :class:`LegVerifier`
(for an arm, a collision check of the straight joint-space leg and a motion planner)
may find a leg longer or impossible when it is asked. Legs are verified lazily, as
GLNS's lazy-edge search evaluates only the edges its best tour uses: :func:`solve_lazy`
asks the verifier about the legs of every new best tour the search finds (never asked
before), writes the corrected times into the search's costs (an impossible leg costs the
problem's ``penalty``, a large finite time, so that the GA avoids it), evaluates its
population again and searches on; its answer uses verified legs only.

The legs are given either densely (an (M, M) matrix over every node, with its block
minima) or as candidate blocks (:class:`~subtask_opt.tour.sparse.SparseLegs`, memory
linear in the targets), searched by :func:`subtask_opt.tour.sparse.search`; a search on
candidate blocks that asks for a pair of targets with no block has it added by the
problem's ``extend``.

:func:`subtask_opt.tour.solve.solve` dispatches a :class:`LazyLegsProblem` here; its
``Result.order`` is the visiting order (home before the first target and after the last),
``configurations`` the node chosen in each target (index within the target),
``leg_times`` the verified leg times of the tour and ``counts`` what the lazy check did.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt._kernel_cache import compile_apart, compile_seconds
from subtask_opt.base.errors import NoPathError, ParameterError, SubtaskOptError
from subtask_opt.base.results import History
from subtask_opt.base.stop import (
    MaxGenerations,
    NoImprovement,
    Progress,
    TargetCost,
    as_criteria,
)
from subtask_opt.tour import clustered as _gc
from subtask_opt.tour.constraints import Canonical, TourConstraints, canonical, checked
from subtask_opt.tour.solve import PINNED_STALL, Result, SolverParams, _relaxation_bound, _rotate
from subtask_opt.tour.sparse import SparseLegs


class LegVerifier:
    """The lazy-cost hook of a :class:`LazyLegsProblem`: what a leg really costs.

    Subclass it (an arm's collision check and detour planner,
    :mod:`subtask_opt.arm.serial_problem`). Legs are named by flat node indices, -1 the
    home, ``a < b``; each is asked about at most once per search round.
    """

    def verify(self, a: int, b: int) -> float | None:
        """None: the leg costs what the problem says; else its true time (a detour's
        time), ``math.inf`` when it is impossible."""
        raise NotImplementedError

    def crowded(self) -> bool:
        """True: checking every new best tour's legs costs too much here (say, it takes
        most of a planning budget); the search then starts again checking whole answers'
        legs only (:func:`solve_lazy`)."""
        return False

    def forget(self) -> None:
        """Forget every leg verified so far (the search starts again from the problem's
        own times)."""


@dataclass(frozen=True, eq=False)
class LazyLegsProblem:
    """A tour from a home through one node of each of N targets (module doc).

    Attributes:
        offsets: (N + 1,) int64; target i owns the nodes offsets[i]..offsets[i+1]-1.
        home_legs: (M,) time between the home and each node (either way).
        penalty: the finite time that stands for an impossible leg (more than any tour of
            possible legs).
        legs: (M, M) symmetric leg times between the nodes, C-contiguous and writable
            (the search writes corrected legs in place and restores them before it
            returns); None with ``sparse``.
        dist: (N, N) the cheapest leg between each two targets (zero diagonal).
        cheapest: (N, M) the cheapest leg between each target and each node.
        sparse: the candidate leg blocks instead of ``legs``, ``dist`` and ``cheapest``.
        bound_inputs: with ``sparse``, the inputs of
            :func:`~subtask_opt.tour.sparse.one_tree_bound` (edges, weights, rho, home).
        extend: with ``sparse``, adds the blocks of the given target pairs (a search
            asked for their legs), keeping the legs already corrected; returns the new
            candidate legs.
        verifier: the lazy-cost hook (None: every leg costs what it says).
    """

    offsets: np.ndarray
    home_legs: np.ndarray
    penalty: float
    legs: np.ndarray | None = None
    dist: np.ndarray | None = None
    cheapest: np.ndarray | None = None
    sparse: SparseLegs | None = None
    bound_inputs: Any = None
    extend: Callable[[list[tuple[int, int]]], SparseLegs] | None = None
    verifier: LegVerifier | None = None

    def __post_init__(self) -> None:
        off = np.asarray(self.offsets)
        if off.ndim != 1 or off.shape[0] < 2 or off[0] != 0 or np.any(np.diff(off) < 1):
            raise ParameterError("LazyLegsProblem.offsets must start at 0 and give every "
                                 f"target at least one node, got {self.offsets!r}")
        m = int(off[-1])
        n = off.shape[0] - 1
        if np.shape(self.home_legs) != (m,):
            raise ParameterError(f"LazyLegsProblem.home_legs must hold {m} times, got shape "
                                 f"{np.shape(self.home_legs)}")
        if not (math.isfinite(self.penalty) and self.penalty > 0):
            raise ParameterError(f"LazyLegsProblem.penalty must be a finite time > 0, got "
                                 f"{self.penalty!r}")
        if self.verifier is not None and not isinstance(self.verifier, LegVerifier):
            raise ParameterError(f"LazyLegsProblem.verifier must be a LegVerifier, got "
                                 f"{self.verifier!r}")
        if (self.legs is None) == (self.sparse is None):
            raise ParameterError("LazyLegsProblem needs either dense legs or sparse ones")
        if self.sparse is not None:
            if self.bound_inputs is None or self.extend is None:
                raise ParameterError("LazyLegsProblem.sparse needs bound_inputs and extend")
            return
        legs = self.legs
        assert legs is not None
        if (legs.shape != (m, m) or legs.dtype != np.float64 or not legs.flags.writeable
                or not legs.flags.c_contiguous):
            raise ParameterError(f"LazyLegsProblem.legs must be a writable C-contiguous "
                                 f"({m}, {m}) float64 array")
        if (self.dist is None or self.cheapest is None or self.dist.shape != (n, n)
                or self.cheapest.shape != (n, m)):
            raise ParameterError(f"LazyLegsProblem.dist and cheapest must be ({n}, {n}) and "
                                 f"({n}, {m})")
    @property
    def size(self) -> int:
        """Number of targets."""
        return int(len(self.offsets) - 1)

    @property
    def symmetric(self) -> bool:
        return True


MAX_ROUNDS = 200
"""Most GA searches of the lazy leg check on dense legs: then the shortest verified answer
stands, or with none :func:`solve_lazy` gives up
(:class:`~subtask_opt.base.errors.NoPathError`)."""
SPARSE_MAX_ROUNDS = 1000
"""Most rounds of the search on candidate legs (the same rule). Most of them only polish
(one decode and local search, O(N)); a cluttered 8-hole cell (``tests/cell/test_cells.py``,
216 of 290 legs checked in collision) takes 262."""
MAX_REPAIRS = 100
"""Most repair rounds in a row before :func:`solve_lazy` runs the GA again."""
LAZY_KICKS = 100
"""Kicks per child of the micro-GA on dense legs from
:data:`~subtask_opt.tour.permutation.KICKS_FROM` targets (the TSP default there is N/10,
at most 100), with :data:`LAZY_STALL_SHARE` of the default stall. On RoboTSP's 245 holes
(seeds 0-7, the legs checked inside the GA): N/10 = 24 kicks and the whole stall (24) gave
tours of median 63.34 s, mean 63.32 s, in a median 1.7 s of search CPU; 100 kicks and half
the stall (12) 63.15 s, 63.25 s in 0.9 s; two thirds (16) 63.15 s, 63.20 s in 1.2 s; 20
generations 63.12 s, 63.12 s in 1.7 s. (Checking the answers after each search and
searching again, as before, 24 kicks and 24 gave 63.24 s, 63.26 s in 2.9 s.) Half keeps
the search within a second or two at the old tours' length; a longer stall buys 0.1-0.2%."""
LAZY_STALL_SHARE = 0.5
"""Share of :meth:`~subtask_opt.tour.solve.SolverParams.default_stop`'s stall the micro-GA
on dense legs keeps from :data:`~subtask_opt.tour.permutation.KICKS_FROM` targets, whose
children carry :data:`LAZY_KICKS` kicks."""
SPARSE_STALL = 5000
"""Kicks without a shorter tour after which the search on candidate legs stops (its
default stop, with :data:`SPARSE_KICKS_PER_TARGET` kicks per target in all)."""
SPARSE_KICKS_PER_TARGET = 20
SPARSE_REPAIR_KICKS = 2000
"""Most kicks of a search round after legs were found impossible or longer, every
:data:`SPARSE_REPAIR_EVERY`-th such round (the others only polish: a round per handful of
corrected legs would otherwise cost kicks each); the first round has the whole budget;
``stop`` applies to each round, a time limit to all of them."""
SPARSE_REPAIR_EVERY = 10
SPARSE_FINAL_ROUNDS = 1
"""Most kicked rounds (of :data:`SPARSE_REPAIR_KICKS`) after a tour verified by polishing
only, searching on knowing every correction so far (in a cluttered cell every kicked round
finds new legs to correct). On 6 targets with a quarter of the legs corrected
(``tests/tour/test_lazy.py``) polishing alone ended 2.1% above the optimum, one such
round at it."""
SPARSE_DEFAULTS = SolverParams()
"""The micro-GA's parameters, none of which a search on candidate legs reads (any other
value is refused)."""


def solve_lazy(problem: LazyLegsProblem, *, seed: int, stop: Any, params: SolverParams,
               constraints: TourConstraints | None, progress: bool, certify: bool,
               certify_time_limit: float) -> Result:
    """:func:`subtask_opt.tour.solve.solve` of a :class:`LazyLegsProblem` (validated there).

    The tour starts at the home and (``tour="closed"``) returns there or (``"open"``) ends
    at its last target; ``constraints.start``/``end`` are the first/last target and
    precedence pairs ``(a, b)`` put target a before b. Dense legs: a plain tour searches
    order and nodes together (the clustered micro-GA, decoded exactly by a layered
    shortest path, :mod:`subtask_opt.tour.clustered`); precedence or a fixed first or
    last target use the pinned clustered GA (:mod:`subtask_opt.tour.pinned_clustered`),
    which keeps every pair and chooses the nodes exactly during the search. Default stop
    ``params.default_stop(N)`` (from ``KICKS_FROM`` targets :data:`LAZY_STALL_SHARE` of
    it, with :data:`LAZY_KICKS` kicks per child unless ``params.kicks`` says otherwise);
    ``params.runs`` independent runs (default one).

    The micro-GA verifies the legs of every new best tour when it is found (``run_ga``'s
    ``on_best``). When the verifier says the problem is crowded
    (:meth:`LegVerifier.crowded`), the search starts again with every leg unverified and
    verifies whole answers' legs after each search instead: when the answer uses a leg
    that proved longer or impossible, the same order is decoded again and polished by the
    local search (a repair round: another node of one of its targets usually avoids it),
    until an answer uses verified legs only; the GA then runs once more from scratch,
    knowing every leg verified so far, and the shorter answer is kept. The GA also runs
    again when a repair cannot avoid the impossible legs, or after :data:`MAX_REPAIRS`
    repairs in a row.

    Every answer carries a lower bound: the Held-Karp bound of the cheapest leg between
    every two targets (and home), below which no tour is (verified legs only get longer).
    ``certify`` proves the answer optimal (Held and Karp's programme over clusters up to
    :data:`~subtask_opt.tour.exact.CLUSTERED_HELD_KARP_MAX` targets, any shape; the
    generalised-TSP branch and cut for larger closed tours without precedence) or says
    why not; impossible legs count as impossible.

    Candidate legs (``problem.sparse``): :func:`subtask_opt.tour.sparse.search`, an
    iterated local search (every kick counts as one generation for ``stop``; default
    :data:`SPARSE_STALL` kicks without improvement or :data:`SPARSE_KICKS_PER_TARGET`
    kicks per target), verifying each answer's legs and searching on from it (polishing
    only, kicks every :data:`SPARSE_REPAIR_EVERY` rounds and, up to
    :data:`SPARSE_FINAL_ROUNDS` times, once more after a tour is verified, knowing every
    correction; the shortest verified tour is the answer); the bound
    is :func:`subtask_opt.tour.sparse.one_tree_bound`. Closed tours only; ``certify`` and
    the micro-GA's ``params`` are refused there.

    Raises:
        ParameterError: constraints or options that do not apply.
        NoPathError: no tour avoids the impossible legs.
    """
    if problem.sparse is not None:
        return _sparse_search(problem, seed, stop, params, constraints, progress, certify)
    shape = _shape(problem, constraints)
    if params.kicks is not None and shape.pinned:
        raise ParameterError("SolverParams.kicks applies to tours without precedence or a "
                             "fixed first or last target (the pinned search has no kicks)")
    blocked: dict[tuple[int, int], float] = {}  # leg (a, b), a < b -> its time
    try:
        return _dense_search(problem, seed, stop, params, blocked, shape, progress, certify,
                             certify_time_limit)
    finally:
        assert problem.legs is not None
        for (a, b), value in blocked.items():
            problem.legs[a, b] = problem.legs[b, a] = value


@dataclass(frozen=True)
class _Shape:
    """A tour's shape in canonical form: nodes 0..N-1 the targets, N the home."""

    constraints: TourConstraints
    canon: Canonical
    closeness: np.ndarray  # (N + 1, N + 1) cheapest leg between targets and home

    @property
    def pinned(self) -> bool:
        return self.canon.needs_pins


def _closeness(problem: LazyLegsProblem) -> np.ndarray:
    """(N + 1, N + 1) cheapest leg between targets and the home (node N)."""
    assert problem.dist is not None
    n = problem.size
    out = np.zeros((n + 1, n + 1))
    out[:n, :n] = problem.dist
    out[n, :n] = out[:n, n] = np.minimum.reduceat(problem.home_legs, problem.offsets[:-1])
    return out


def _shape(problem: LazyLegsProblem, constraints: TourConstraints | None) -> _Shape:
    """Validate ``constraints`` for a tour from the problem's home and put them in
    canonical form (a first or last target as precedence pairs, an open path's free
    return to the home)."""
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
    closeness = _closeness(problem)
    # the home is node N, where the canonical tour starts (a closed tour returns there,
    # an open path's return is free)
    canon_cons = TourConstraints(tour=constraints.tour, start=n, end=end,
                                 precedence=tuple(dict.fromkeys(pairs)))
    canon = canonical(closeness, canon_cons, default_start=n)
    return _Shape(constraints, canon, closeness)


def _search_defaults(params: SolverParams, n: int) -> tuple[list[Any], int | None]:
    """The default stop and the kicks of the micro-GA on dense legs for ``n`` targets
    (``params.kicks`` as given, else :data:`LAZY_KICKS` from ``KICKS_FROM`` targets)."""
    from subtask_opt.tour.permutation import KICKS_FROM

    stop = params.default_stop(n)
    if n < KICKS_FROM or params.preset == "paper":
        return stop, params.kicks
    stop = [NoImprovement(max(1, round(c.generations * LAZY_STALL_SHARE)))
            if isinstance(c, NoImprovement) else c for c in stop]
    return stop, LAZY_KICKS if params.kicks is None else params.kicks


class _Crowded(Exception):
    """Raised through the GA by its lazy leg check when the verifier is crowded."""


def _dense_search(problem: LazyLegsProblem, seed: int, stop: Any, params: SolverParams,
                  blocked: dict[tuple[int, int], float], shape: _Shape, progress: bool,
                  certify: bool, certify_time_limit: float) -> Result:
    """:func:`solve_lazy` on dense legs; every leg it corrects in the problem's legs goes
    into ``blocked`` with its time first."""
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.chromosomes import use
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

    assert problem.legs is not None and problem.dist is not None
    assert problem.cheapest is not None
    n = problem.size
    verifier = problem.verifier
    cpu = {"search": 0.0, "compile": 0.0, "verify": 0.0}
    penalty = problem.penalty
    search = SEARCH_PAPER if params.preset == "paper" else SEARCH_FAST
    config = GAConfig(population=params.population, elite=1, crossover_rate=1.0,
                      mutation_rate=0.0, restart_on_convergence=True,
                      convergence_tol=params.convergence_tol)
    off = problem.offsets
    verified: dict[tuple[int, int], bool] = {}  # (from, to) flat index, -1 = home -> longer
    generations = restarts = 0
    rounds = ga_rounds = repairs = 0
    t0 = time.process_time()
    canon = shape.canon
    open_path = canon.open_path
    # the legs are symmetric, so a closed tour's search uses neighbour lists over targets +
    # home; an open path's free return to the home is not, so it searches exactly
    home_in = problem.home_legs
    if open_path:
        home_in = np.zeros_like(problem.home_legs)
        search = SEARCH_PAPER if params.preset == "paper" else SEARCH_EXACT
    data = _gc.ConfiguredData(np.array(problem.dist), off, problem.legs,
                              np.array(problem.home_legs), np.array(home_in), float(search),
                              (np.zeros((0, 0), dtype=np.int64) if open_path
                               else _near(shape.closeness, params.neighbours)),
                              np.zeros((0, 0)) if open_path else problem.cheapest)
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
    repair = False  # True: the last round corrected legs of the current order
    again = False  # True: search once more knowing the legs verified
    best: tuple[float, np.ndarray, np.ndarray] | None = None  # best verified answer
    pinned_dist: list[np.ndarray] = []  # the pinned kind's target costs, kept like data.dist
    plain_rounds = 0  # GA rounds that did not verify legs as they went

    def check_legs(tour: list[int]) -> bool:
        """Verify the legs of ``tour`` (flat nodes, -1 = home) not verified before; one
        that proves longer costs its true time (an impossible one the penalty) from now on
        (in ``data``, in place). Returns whether any did."""
        if verifier is None:
            return False
        found = False
        t0 = time.process_time()
        for a, b in zip(tour[:-1], tour[1:], strict=True):
            key = (min(a, b), max(a, b))
            if key in verified:
                continue  # verified before: its cost is exact
            true = verifier.verify(*key)
            verified[key] = true is not None
            if true is None:
                continue
            found = True
            cost = penalty if math.isinf(true) else float(true)
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
        cpu["verify"] += time.process_time() - t0
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
        if verifier is not None and verifier.crowded():
            raise _Crowded
        return found

    def forget_checks() -> None:
        """Every leg back to the problem's time, as before any check."""
        for (a, b), value in blocked.items():
            data.legs[a, b] = data.legs[b, a] = value
        blocked.clear()
        data.dist[:] = problem.dist
        data.home_out[:] = problem.home_legs
        data.home_in[:] = home_in
        verified.clear()
        if verifier is not None:
            verifier.forget()

    on_best = check_best if verifier is not None else None
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
                break  # the verified answer found so far stands
            if ga_rounds >= MAX_ROUNDS:
                raise NoPathError(f"impossible legs still in the best tour after "
                                  f"{ga_rounds} searches")
            repairs = 0
            again = False
            default_stop, round_kicks = _search_defaults(params, n)
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
            with compile_apart(cpu) as compiled, progress_bar(
                    progress, total=total, desc=f"micro-GA round {ga_rounds}",
                    unit="gen") as bar:
                on_chunk = _reporter(bar)
                try:
                    if shape.pinned:  # the order and the nodes together, pairs kept
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
                except _Crowded:
                    outcome = None
            t0 += compiled[0] + in_ga[0]  # not search time
            if outcome is None:
                # so crowded that verifying the new bests' legs costs too much: verify whole
                # answers' legs after each search instead (repairs, then a second search
                # knowing them)
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
            break  # a later search found nothing better than the verified answer
        if cost >= penalty:
            raise NoPathError(
                f"no tour avoids the legs in collision ({sum(verified.values())} legs of "
                f"{len(verified)} checked collide); try a larger axis step sampling, another "
                "home or fewer obstacles")
        repair = check_legs(tour)  # a cost of this tour was corrected: decode it again
        if not repair:
            if best is None or cost < best[0]:
                best = (cost, genes.copy(), choice.copy())
            if on_best is None and plain_rounds == 1 and any(verified.values()):
                again = True
                continue
            break
    assert best is not None  # the loop ends only after recording a verified answer
    cost, order, index = best
    broken = canon.violations(np.concatenate([[n], order]))
    if broken:  # the operators keep every constraint: this is a bug, never an answer
        raise SubtaskOptError(f"internal error: the answer breaks its constraints: {broken}")
    nodes = [-1] + [int(off[t] + index[t]) for t in order] + ([] if open_path else [-1])
    legs = np.array([_dense_leg(data, a, b) for a, b in zip(nodes[:-1], nodes[1:],
                                                             strict=True)])
    certified = None
    if certify:
        t0 = time.process_time()
        certified = _certify(problem, data, shape, order, index, float(legs.sum()),
                             certify_time_limit)
        cpu["certify"] = time.process_time() - t0
    counts = {"legs_checked": len(verified), "legs_infeasible": int(sum(verified.values())),
              "search_rounds": rounds, "ga_rounds": ga_rounds}
    return Result(order=order, total_time=float(legs.sum()), leg_times=legs,
                  matrix=np.zeros((0, 0)), generations=generations, restarts=restarts,
                  runtime_s=runtime, seed=seed, history=history, preset=params.preset,
                  lower_bound=bound, certified=certified, constraints=shape.constraints,
                  start=None, runs=max(runs, 1), configurations=index, cpu=cpu,
                  counts=counts)


def _dense_leg(data: _gc.ConfiguredData, a: int, b: int) -> float:
    """The search's time of the leg between flat nodes a and b (-1 the home)."""
    if a < 0:
        return float(data.home_out[b])
    if b < 0:
        return float(data.home_in[a])
    return float(data.legs[a, b])


def _certify(problem: LazyLegsProblem, data: Any, shape: _Shape, order: np.ndarray,
             index: np.ndarray, total: float, time_limit: float) -> str:
    """Prove ``total`` optimal over every order and node, or say why not.

    Up to :data:`~subtask_opt.tour.exact.CLUSTERED_HELD_KARP_MAX` targets, any shape:
    Held and Karp's programme over (targets visited, node last visited), precedence and a
    fixed first or last target kept. Larger closed tours without precedence: the
    generalised-TSP branch and cut (:func:`~subtask_opt.tour.exact.gtsp_optimum`, the
    home a cluster of one node). Legs found impossible count as impossible (no feasible
    tour uses one)."""
    from subtask_opt.tour.exact import CLUSTERED_HELD_KARP_MAX, clustered_held_karp, gtsp_optimum

    canon = shape.canon
    n = problem.size
    m = int(problem.offsets[-1])
    counts = np.diff(problem.offsets)
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
            owner = np.repeat(np.arange(n + 1), np.append(counts, 1))
            incumbent = [m] + [int(problem.offsets[t] + index[t]) for t in order]
            optimum = gtsp_optimum(cost, owner, incumbent=incumbent,
                                   time_limit=time_limit)[0]
    except SubtaskOptError as exc:
        return f"not certified: {exc}"
    if total <= optimum * (1 + 1e-9) + 1e-12:
        return "optimal (proven, planned times)"
    return (f"not optimal: the proven optimum of the planned times is {optimum:.6g} "
            f"({100 * (total / optimum - 1):.4f}% less)")


MAX_CERTIFY_NODES = 3000
"""Most nodes :func:`solve_lazy` hands its certificate's branch and cut."""


def _reporter(bar: Any) -> Callable[[Progress], None]:
    """A GA chunk callback that moves ``bar`` to the generation reached."""
    done = [0]

    def on_chunk(p: Progress) -> None:
        bar.update(p.generation - done[0])
        done[0] = p.generation
        bar.set_postfix_str(f"best {p.best_cost:.4f}")
    return on_chunk


def _near(closeness: np.ndarray, k: int) -> np.ndarray:
    """(N + 1, k) nearest nodes of each target and home (node N) by their cheapest legs."""
    from subtask_opt.tour.permutation import neighbour_table

    return neighbour_table(closeness, k)


def _sparse_search(problem: LazyLegsProblem, seed: int, stop: Any, params: SolverParams,
                   constraints: TourConstraints | None, progress: bool,
                   certify: bool) -> Result:
    """:func:`solve_lazy` on candidate legs (:mod:`subtask_opt.tour.sparse`): the iterated
    local search (each kick counts as a generation for ``stop``), the lazy leg check (a
    leg the verifier corrects is marked in the candidate legs, and the search resumes from
    the same tour), the blocks of target pairs that are not candidates added when an
    answer uses one, and the sparse 1-tree bound."""
    from subtask_opt.base.progress import progress_bar
    from subtask_opt.tour import sparse as ts

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
    changed = [f for f in ("preset", "population", "convergence_tol", "grasp_share",
                           "max_segment", "neighbours", "paper_loop", "runs",
                           "bound_max_nodes", "kicks")
               if getattr(params, f) != getattr(SPARSE_DEFAULTS, f)]
    if changed:
        raise ParameterError(f"SolverParams.{changed[0]} applies to the micro-GA of dense "
                             "legs, not to a problem on candidate legs (legs_mode 'sparse')")
    assert problem.extend is not None
    n = problem.size
    verifier = problem.verifier
    cpu = {"search": 0.0, "compile": 0.0, "bound": 0.0, "verify": 0.0}
    kicks = SPARSE_KICKS_PER_TARGET * n + 1000
    criteria = as_criteria(stop, [NoImprovement(SPARSE_STALL), MaxGenerations(kicks)])
    for c in criteria:
        if isinstance(c, MaxGenerations):
            kicks = c.generations
    started = time.monotonic()
    # per search round: its first kick, best time and the kick that found it (a repair
    # round starts afresh: its tour holds legs just corrected, so it is longer than before)
    state: dict[str, Any] = {"best": math.inf, "at": 0, "done": 0, "start": 0}

    def should_stop() -> bool:
        p = Progress(int(state["done"] - state["start"]), float(state["best"]),
                     int(state["done"] - state["at"]),
                     time.monotonic() - started)
        return any(c(p) for c in criteria)

    history_cost: list[float] = []
    verified: dict[tuple[int, int], bool] = {}
    tour = choice = None
    done_total = rounds = 0
    final = corrected = False  # a kicked round is due / legs corrected since the last one
    finals = 0
    best: tuple[float, np.ndarray, np.ndarray] | None = None  # the shortest verified tour
    t0 = time.process_time()
    with compile_apart(cpu) as compiled, progress_bar(progress, total=kicks,
                                                      desc="search (kicks)",
                                                      unit="kick") as bar:
        while True:
            rounds += 1
            state.update(best=math.inf, at=done_total, start=done_total)
            # after legs were corrected: polish only (re-decode around them), with kicks
            # every SPARSE_REPAIR_EVERY rounds
            budget = kicks if rounds == 1 else (
                min(kicks, SPARSE_REPAIR_KICKS) if final or rounds % SPARSE_REPAIR_EVERY == 0
                else 0)
            kicked = budget > 0

            def on_chunk(done: int, best: float, base: int = done_total) -> None:
                if best < state["best"] - 1e-12:
                    state["best"], state["at"] = best, base + done
                    history_cost.append(best)
                bar.update(base + done - state["done"])
                state["done"] = base + done
                bar.set_postfix_str(f"best {best:.4f}")

            assert problem.sparse is not None
            out = ts.search(problem.sparse, seed=seed + rounds - 1,
                            kicks=budget, tour=tour, choice=choice,
                            should_stop=should_stop, on_chunk=on_chunk)
            done_total += out.kicks
            tour, choice = out.tour, out.choice
            missing = [(int(a), int(b)) for a, b in zip(tour[1:-2], tour[2:-1], strict=True)
                       if not np.any(problem.sparse.nbr[a] == b)]
            if missing:  # the legs the search asked for: add them and search on
                object.__setattr__(problem, "sparse", problem.extend(missing))
                continue
            repair = False
            if verifier is not None:
                tv = time.process_time()
                with compile_seconds() as in_verify:  # counted apart already
                    flat = [-1 if t == n else int(problem.offsets[t] + choice[t]) for t in tour]
                    for a, b in zip(flat[:-1], flat[1:], strict=True):
                        key = (min(a, b), max(a, b))
                        if key in verified:
                            continue
                        true = verifier.verify(*key)
                        verified[key] = true is not None
                        if true is not None:
                            mark_sparse_leg(problem.sparse, a, b, problem.penalty
                                            if math.isinf(true) else float(true))
                            repair = True
                tc = time.process_time() - tv
                tc -= min(in_verify[0], tc)
                cpu["verify"] += tc
                t0 += tc
            corrected = repair or (corrected and not kicked)
            if not repair and (best is None or out.cost < best[0]):
                best = (float(out.cost), tour.copy(), choice.copy())
            if not repair and (not corrected or finals == SPARSE_FINAL_ROUNDS):
                break  # verified, and searched with kicks since the last correction
            # verified after polishing only: search once more with kicks, knowing every
            # correction (at most SPARSE_FINAL_ROUNDS times; the shortest verified tour
            # stands)
            final = not repair
            finals += final
            if rounds >= SPARSE_MAX_ROUNDS and best is not None:
                break  # the shortest verified tour stands
            if rounds >= SPARSE_MAX_ROUNDS:
                raise NoPathError(f"legs in collision still in the best tour after {rounds} "
                                  "searches")
    cpu["search"] += time.process_time() - t0 - compiled[0]
    assert best is not None  # the loop ends only after a verified tour
    cost, tour, choice = best
    if cost >= problem.penalty:
        raise NoPathError(f"no tour avoids the legs in collision ({sum(verified.values())} "
                          f"legs of {len(verified)} checked collide)")
    order = tour[1:-1].astype(np.int64)
    index = choice.astype(np.int64)
    with compile_apart(cpu) as compiled:
        tb = time.process_time()
        edges, weights, rho, home_min = problem.bound_inputs
        bound = ts.one_tree_bound(n, edges, weights, rho, home_min, upper=cost)
        cpu["bound"] += time.process_time() - tb
    cpu["bound"] -= compiled[0]
    sp = problem.sparse
    legs = np.array([ts.leg(sp, int(a), int(index[a]) if a < n else 0, int(b),
                            int(index[b]) if b < n else 0)
                     for a, b in zip(tour[:-1], tour[1:], strict=True)])
    counts = {"legs_checked": len(verified), "legs_infeasible": int(sum(verified.values())),
              "search_rounds": rounds, "ga_rounds": 0, "kicks": done_total,
              "candidate_legs": int(sp.legs.size)}
    costs = np.array(history_cost) if history_cost else np.array([cost])
    history = History(float(costs[0]), costs, costs.copy())
    return Result(order=order, total_time=float(legs.sum()), leg_times=legs,
                  matrix=np.zeros((0, 0)), generations=done_total, restarts=0,
                  runtime_s=time.monotonic() - started, seed=seed, history=history,
                  preset=params.preset, lower_bound=bound, certified=None, constraints=cons,
                  start=None, runs=1, configurations=index, cpu=cpu, counts=counts)


def _owner(offsets: np.ndarray, a: int) -> int:
    return int(np.searchsorted(offsets, a, side="right") - 1)


def sparse_leg_time(data: SparseLegs, a: int, b: int) -> float:
    """The stored time of the leg between flat nodes a and b (-1: the home)."""
    from subtask_opt.tour.sparse import leg

    if a < 0 and b < 0:
        return 0.0
    if a < 0 or b < 0:
        return float(data.home[max(a, b)])
    off = data.offsets
    ta, tb = _owner(off, a), _owner(off, b)
    return float(leg(data, ta, a - off[ta], tb, b - off[tb]))


def mark_sparse_leg(data: SparseLegs, a: int, b: int, value: float) -> None:
    """Set the leg between flat nodes a and b (-1: the home) to ``value`` both ways, in
    place; the targets' block must be stored (a home leg always is)."""
    if a < 0 or b < 0:
        data.home[max(a, b)] = value
        return
    off = data.offsets
    ta, tb = _owner(off, a), _owner(off, b)
    for u, cu, v, cv in ((ta, a - off[ta], tb, b - off[tb]), (tb, b - off[tb], ta,
                                                              a - off[ta])):
        slots = np.flatnonzero(data.nbr[u] == v)
        if slots.size == 0:
            raise ParameterError(f"no stored block between targets {u} and {v}")
        data.legs[data.start[u, int(slots[0])] + cu * (off[v + 1] - off[v]) + cv] = value


__all__ = ["LAZY_KICKS", "LAZY_STALL_SHARE", "MAX_REPAIRS", "MAX_ROUNDS", "LazyLegsProblem",
           "LegVerifier", "mark_sparse_leg", "solve_lazy", "sparse_leg_time"]
