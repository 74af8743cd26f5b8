"""Solve a tour problem: the micro-GA, the lower bound and the certificate.

:func:`solve` finds a minimum-cost closed tour (or an open path, a tour from a home,
with precedence) over a :class:`~subtask_opt.tour.problem.MatrixProblem` or a
:class:`~subtask_opt.tour.problem.ClusteredProblem`, with the micro genetic algorithm of
the paper (``preset="paper"``) or with our default, a micro-GA whose children are
polished by local search. Every answer carries the Held-Karp lower bound (up to
``SolverParams.bound_max_nodes`` nodes) and, on request, an exact certificate.

>>> import numpy as np
>>> from subtask_opt.tour import MatrixProblem, solve
>>> points = np.random.default_rng(0).random((20, 2))
>>> costs = np.hypot(*(points[:, None] - points[None]).transpose(2, 0, 1))
>>> result = solve(MatrixProblem(costs), seed=1)
>>> print(result.summary())  # doctest: +SKIP
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.base.errors import (
    NoPathError,
    ParameterError,
    SubtaskOptError,
    require_in_range,
    require_int,
)
from subtask_opt.base.progress import progress_bar
from subtask_opt.base.results import History
from subtask_opt.base.stop import (
    MaxGenerations,
    NoImprovement,
    Progress,
    StoppingCriterion,
    TargetCost,
    as_criteria,
)
from subtask_opt.chromosomes import use
from subtask_opt.ga.config import GAConfig
from subtask_opt.ga.kinds import Kind
from subtask_opt.ga.loop import MAX_RUNS, run_ga
from subtask_opt.tour.bound import candidate_table, lower_bound
from subtask_opt.tour.clustered import ConfiguredData
from subtask_opt.tour.configurations import penalty_for
from subtask_opt.tour.constraints import (
    Canonical,
    TourConstraints,
    canonical,
    checked,
    symmetric_path_matrix,
    transform_tensor,
)
from subtask_opt.tour.permutation import (
    KICKS_FROM,
    SEARCH_EXACT,
    SEARCH_FAST,
    SEARCH_PAPER,
    PermutationAux,
    make_aux,
    neighbour_table,
)
from subtask_opt.tour.pinned_clustered import (
    PinnedClusteredData,
    make_data,
    make_pinned_clustered_aux,
)
from subtask_opt.tour.precedence import PinnedAux, make_pinned_aux
from subtask_opt.tour.problem import (
    MAX_NODES,
    ClusteredProblem,
    GtspProblem,
    MatrixProblem,
    TourProblem,
)

if TYPE_CHECKING:
    from subtask_opt.tour.lazy import LazyLegsProblem

PRESETS = ("default", "paper")
MAX_KICKS = 1000
"""Most kicks per child :class:`SolverParams` accepts."""
CONFIGURED_RUNS = 12
"""Independent runs of the default search when it chooses configurations below
:data:`~subtask_opt.tour.permutation.KICKS_FROM` subtasks, each stalling two thirds as long
as a fixed-configuration search (a third of what a single run had). On the 11 hardest
held-out sets of ``benchmarks/heldout.py`` (30-60 subtasks, both robots, 60 seeds each)
one run at the old stall ended in a slightly longer local optimum (one of two or three per
set) in 43 of 660 runs, and at a third of that stall in 129 (``benchmarks/runs.py``).
Shorter runs are cheaper than they are worse: from the per-run miss rates, the expected
misses over those sets x 20 seeds are 0.42 for 3 runs at the old stall (3x its time), 0.04
for 8 at a third of it (3x) and 0.001 for 12 (4.6x). 8 runs still missed 1 of 840 held-out
runs (planar_2r random60/5002, whose runs miss 45% of the time), hence 12."""
PAPER_LOOP = GAConfig(population=5, elite=1, crossover_rate=1.0, mutation_rate=0.0,
                      restart_on_convergence=True, pairing="double", convergence="cost",
                      convergence_tol=0.01, crossover_start="random", distinct_mates=True)
"""The paper preset's micro-GA loop: the reading of the paper (seed 002, III-2) that
``benchmarks/paper_micro_ga.py`` found closest to its generation counts: the best
string kept; "8 pairs" of strings that differ mated, the better 4 children kept;
greedy crossover from a random city; restart (best + 4 random strings) when the
costs are within 1% or stopped changing; no mutation."""


@dataclass(frozen=True)
class SolverParams:
    """How :func:`solve` searches.

    Attributes:
        preset: ``"paper"`` is the paper's micro-GA (population 5, elitism,
            greedy crossover with a random fallback, random restarts on
            convergence, no mutation, no local search), with the pairing and
            convergence test of :data:`PAPER_LOOP` (the paper leaves them open).
            ``"default"`` keeps a random-pairing loop and adds what makes it fast and
            reliable: nearest-city fallback in the crossover, a 2-opt/Or-opt
            local search around every change, and restarts that mix kicks of
            the best tour with randomised nearest-neighbour tours.
        population: micro-GA population size (the paper: 5).
        convergence_tol: (default preset) relative cost spread below which the
            population counts as converged and restarts (the paper preset's test
            is ``paper_loop``'s).
        grasp_share: (default preset) share of restart individuals built by
            randomised nearest neighbour instead of kicking the best tour.
        max_segment: (default preset) longest run of subtasks Or-opt moves.
        neighbours: (default preset) candidate list length of the local search.
        bound_max_nodes: compute a Held-Karp lower bound (and stop as soon as a
            tour meets it) for problems up to this many nodes; 0 never.
        paper_loop: (paper preset) how the loop reads the paper's micro-GA
            (pairing, convergence test, crossover start; see
            :class:`~subtask_opt.ga.config.GAConfig`); None: :data:`PAPER_LOOP`
            with ``population``. A given loop is used as it is (its population and
            convergence test replace ``population`` and ``convergence_tol``).
        runs: independent GA runs, each from a fresh population until the
            stop holds (see :func:`~subtask_opt.ga.loop.run_ga`), the best answer
            kept; None: :meth:`default_runs`.
        kicks: (default preset, no precedence or fixed end) kicks of the iterated local
            search per child and restart individual, in 0..:data:`MAX_KICKS`
            (:func:`~subtask_opt.tour.permutation.make_aux`); None: its default for the
            size (N/10, at most 100, from ``KICKS_FROM`` nodes; on lazily verified legs
            :data:`~subtask_opt.tour.lazy.LAZY_KICKS`).
    """

    preset: str = "default"
    population: int = 5
    bound_max_nodes: int = 300
    convergence_tol: float = 0.01
    grasp_share: float = 0.25
    max_segment: int = 3
    neighbours: int = 8
    paper_loop: GAConfig | None = None
    runs: int | None = None
    kicks: int | None = None

    def __post_init__(self) -> None:
        if self.paper_loop is not None and not isinstance(self.paper_loop, GAConfig):
            raise ParameterError(f"SolverParams.paper_loop must be a GAConfig or None, "
                                 f"got {self.paper_loop!r}")
        if self.paper_loop is not None and self.preset != "paper":
            raise ParameterError(f"SolverParams.paper_loop applies to the paper preset only, "
                                 f"got preset {self.preset!r}")
        if self.preset not in PRESETS:
            raise ParameterError(
                f"SolverParams.preset must be one of {', '.join(PRESETS)}, got {self.preset!r}")
        require_int("SolverParams", "population", self.population, 3, 1000)
        require_in_range("SolverParams", "convergence_tol", self.convergence_tol, 0.0, 1.0)
        require_in_range("SolverParams", "grasp_share", self.grasp_share, 0.0, 1.0)
        require_int("SolverParams", "max_segment", self.max_segment, 1, 1000)
        require_int("SolverParams", "neighbours", self.neighbours, 1, 1000)
        require_int("SolverParams", "bound_max_nodes", self.bound_max_nodes, 0, MAX_NODES)
        if self.runs is not None:
            require_int("SolverParams", "runs", self.runs, 1, MAX_RUNS)
        if self.kicks is not None:
            require_int("SolverParams", "kicks", self.kicks, 0, MAX_KICKS)
            if self.preset == "paper":
                raise ParameterError("SolverParams.kicks applies to the default preset (the "
                                     "paper's micro-GA has no local search)")

    @classmethod
    def paper(cls) -> SolverParams:
        return cls(preset="paper")

    def default_stop(self, size: int = 30, *,
                     configured: bool = False) -> list[StoppingCriterion]:
        """Stopping criteria used when :func:`solve` is given none, for ``size`` nodes;
        ``configured``: the search also chooses each subtask's configuration (a
        generalised TSP), whose local optima are deeper: below
        :data:`~subtask_opt.tour.permutation.KICKS_FROM` nodes (from there on every child
        carries N/10 kicks) it makes :data:`CONFIGURED_RUNS` runs of two thirds of the
        stall each (:meth:`default_runs`)."""
        if self.preset == "paper":
            return [NoImprovement(2000), MaxGenerations(50_000)]
        # 15 stalled generations reach the certified optimum of every built-in
        # 30-subtask instance in benchmarks/sequencing.py. On the held-out 60-subtask
        # sets of benchmarks/heldout.py 15 missed 12 of 400 fixed-configuration runs
        # and 40 still 1 of 120 on its hardest sets; 100 missed none. So the stall
        # grows from 15 at 30 nodes to 100 at 60, then keeps about 6000 stalled kicks
        # (each generation's iterated local search kicks about once per node), never
        # below the slow growth that suits large tours (benchmarks/growth.py).
        # Choosing configurations too, a run ends in one of a few deep local optima
        # whatever its stall, so several shorter runs beat one long one: see
        # CONFIGURED_RUNS.
        # From 1000 nodes on a search whose children carry 100 kicks each keeps finding
        # shorter tours, so the stall alone let N = 3200 run 343 generations (21 s of CPU)
        # for a tour 0.2% shorter than after 40 (3 s): the generations are capped too
        # (:data:`LARGE_GENERATIONS`; pr1002 ends after 33-48 by its stall).
        stall = max(15, min(15 + 3 * max(0, size - 30), 6000 // size), 10 + size // 100)
        if configured and size < KICKS_FROM:
            stall = 2 * stall // 3  # each of CONFIGURED_RUNS runs (see default_runs)
        return [NoImprovement(stall), MaxGenerations(generation_cap(size))]

    def default_runs(self, size: int = 30, *, configured: bool = False) -> int:
        """Independent runs :func:`solve` makes (``runs``, or for ``size`` nodes,
        ``configured`` as in :meth:`default_stop`).

        Choosing configurations below :data:`~subtask_opt.tour.permutation.KICKS_FROM`
        nodes, a run falls into one of two or three deep local optima and stays
        there however long it stalls: :data:`CONFIGURED_RUNS` runs. Otherwise one.
        """
        if self.runs is not None:
            return self.runs
        if configured and size < KICKS_FROM and self.preset != "paper":
            return CONFIGURED_RUNS
        return 1


LARGE_GENERATIONS = 64_000
"""The default stop's generations from 1000 nodes on: at most ``LARGE_GENERATIONS / N``
(64 at N = 1000, 40 at N = 1600, 20 from N = 3200), never fewer than
:data:`FEWEST_GENERATIONS` (:func:`generation_cap`)."""
FEWEST_GENERATIONS = 20
"""The default stop's cap never goes below this. At N = 3200 (uniform points, seed 0) 20
generations take 2.3 s of CPU for length / sqrt(N) 0.7293, 40 take 4.1 s for 0.7277
(v0.1: 4.2 s for 0.7545 in the same run): the second 20 bought 0.2% for 45% of the CPU."""


def generation_cap(size: int) -> int:
    """Most generations of the default stop for ``size`` nodes: 50 000 below 1000 nodes,
    then :data:`LARGE_GENERATIONS` / N, at least :data:`FEWEST_GENERATIONS` (one
    generation polishes its children with 100 kicks each; at N = 3200 one takes about
    0.06 s of CPU)."""
    return 50_000 if size < 1000 else max(FEWEST_GENERATIONS, LARGE_GENERATIONS // size)


@dataclass(frozen=True)
class Result:
    """The answer of :func:`solve`: the tour and the facts of the search.

    Attributes:
        order: 0-based indices of the closed tour, starting at the problem's
            ``first`` node (or node 0).
        total_time: time of the closed tour (seconds under the time model).
        leg_times: ``leg_times[i]`` is the time from ``order[i]`` to
            ``order[(i + 1) % N]``.
        matrix: the N x N travel times of the answer (for an arm problem that
            optimises configurations: at the configurations chosen; with a home
            point, (N + 1) x (N + 1), the home last).
        generations, restarts, runs: what the micro-GA did (over its independent runs).
        runtime_s: wall time of the search (compilation never included).
        seed: the seed that reproduces this result.
        history: best and mean cost per generation, restart generations.
        preset: the solver preset.
        lower_bound: no tour of the problem is shorter (Held-Karp 1-tree bound,
            see :mod:`subtask_opt.tour.bound`); None when not computed.
        gap_bound: ``(total_time - lower_bound) / lower_bound``, the largest
            relative distance from the optimum this answer can have (0: proven
            optimal).
        certified: ``"optimal (proven)"`` when the MILP proved the answer optimal,
            the reason otherwise (``solve(..., certify=True)``); None when not asked.
        report: for an arm problem, what the tour means for the arm
            (:class:`~subtask_opt.arm.report.TourReport`); None for a tour problem.
            With a home it describes the closed tour through the home (the
            last subtask row); for an open path, the tour closed by its return.
        configurations: the node chosen in each cluster (by cluster index) of a
            clustered problem; the vertex chosen in each set (by set index) of a
            :class:`~subtask_opt.tour.problem.GtspProblem`; an arm problem's (N, n)
            joint vector of every target (input order); None for a matrix problem.
        cpu: CPU seconds per phase of an arm problem (``ik``, ``collision``,
            ``matrix``, ``search``, and numba's ``compile`` apart); of a
            :class:`~subtask_opt.tour.lazy.LazyLegsProblem`, its search's (``search``,
            ``verify``, ``compile``); empty for another tour problem.
        counts: what the lazy leg check of a
            :class:`~subtask_opt.tour.lazy.LazyLegsProblem` did (legs checked, legs
            corrected as ``legs_infeasible``, search rounds); empty otherwise.
        constraints: the tour shape and precedence the answer keeps
            (:class:`~subtask_opt.tour.constraints.TourConstraints`).
        start: the subtask the answer starts at (None with a home).

    With constraints (see :mod:`subtask_opt.tour.constraints`) the answer is in
    your terms: ``order`` leaves the home out, ``leg_times`` are the legs
    driven (with a home: home -> order[0], ..., order[-1] -> home, N + 1 legs;
    an open path: N - 1 legs, no return) and ``total_time`` is their sum.
    """

    order: np.ndarray
    total_time: float
    leg_times: np.ndarray
    matrix: np.ndarray
    generations: int
    restarts: int
    runtime_s: float
    seed: int
    history: History
    preset: str
    lower_bound: float | None = None
    certified: str | None = None
    report: Any = None
    constraints: TourConstraints = field(default_factory=TourConstraints)
    start: int | None = None
    runs: int = 1
    configurations: np.ndarray | None = None
    cpu: dict[str, float] = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=dict)

    @property
    def gap_bound(self) -> float | None:
        if self.lower_bound is None or self.lower_bound <= 0:
            return None
        return max(0.0, (self.total_time - self.lower_bound) / self.lower_bound)

    def summary(self) -> str:
        """A few lines for a terminal."""
        lines = []
        if self.report is not None:
            lines.append(self.report.header(len(self.order)))
        lines += [
            f"total time {self.total_time:.4f} s  ({self.preset} preset, seed {self.seed}, "
            f"{self.generations} generations, {self.restarts} restarts"
            + (f" in {self.runs} runs" if self.runs > 1 else "")
            + f", {self.runtime_s * 1e3:.2f} ms)",
        ]
        if self.lower_bound is not None:
            gap = self.gap_bound
            lines.append(f"lower bound {self.lower_bound:.4f} s (gap at most "
                         f"{100 * gap:.3f}%)" if gap is not None else
                         f"lower bound {self.lower_bound:.4f} s")
        if self.certified is not None:
            lines.append(f"certificate: {self.certified}")
        if not self.constraints.is_plain:
            c = self.constraints
            where = (f"home {c.home}" if c.home is not None else
                     f"from {'home' if self.start is None else self.start}"
                     + (f" to {c.end}" if c.end is not None else ""))
            lines.append(f"shape: {c.tour} tour, {where}, {len(c.precedence)} precedence "
                         "constraints")
        lines.append("order: " + " ".join(str(int(i)) for i in self.order))
        if self.report is not None:
            lines += self.report.order_lines(self.order)
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (the CLI's ``--json``); the arm's view under ``"report"``."""
        return {
            "order": [int(i) for i in self.order],
            "total_time": self.total_time,
            "leg_times": self.leg_times.tolist(),
            "matrix": self.matrix.tolist(),
            "generations": self.generations,
            "restarts": self.restarts,
            "runs": self.runs,
            "runtime_s": self.runtime_s,
            "seed": self.seed,
            "preset": self.preset,
            "lower_bound": self.lower_bound,
            "gap_bound": self.gap_bound,
            "certified": self.certified,
            **self.constraints.describe(),
            "start": self.start,
            "precedence": len(self.constraints.precedence),
            "history": self.history.to_dict(),
            "configurations": (None if self.configurations is None
                               else np.asarray(self.configurations).tolist()),
            "report": None if self.report is None else self.report.to_dict(),
        }



def solve(problem: TourProblem | LazyLegsProblem, *, seed: int = 0,
          stop: StoppingCriterion | list[StoppingCriterion] | None = None,
          params: SolverParams | None = None, progress: bool = False,
          certify: bool = False, certify_time_limit: float = 60.0,
          constraints: TourConstraints | None = None) -> Result:
    """Find a minimum-time closed tour through the problem's subtasks (or nodes).

    Args:
        problem: what to solve (a matrix or a clustered problem, or a
            :class:`~subtask_opt.tour.problem.GtspProblem` of sets of any size, as
            :mod:`~subtask_opt.tour.gtsplib` reads them; arm problems go through
            :func:`subtask_opt.solve`, which compiles them into one).
        seed: random seed in [0, 2**63); the same seed gives the same result.
        stop: one stopping criterion or a list (any of them stops the run);
            default: ``params.default_stop(N, configured=...)`` (``configured``: the
            problem chooses its configurations).
        params: solver parameters (default: ``SolverParams()``).
        progress: show a progress bar on stderr (a terminal only) for runs over a second.
        certify: prove optimality within ``certify_time_limit`` seconds with an exact
            method (a MILP over the order for fixed configurations; branch and cut over
            order and configurations when they are chosen, or with precedence or an open
            path the arc MILP of :func:`~subtask_opt.tour.exact.milp_pinned_clustered`);
            the outcome is in :attr:`Result.certified`.
        constraints: the tour shape (closed from a start, open to a fixed or
            free end, a home visited first and last) and precedence pairs
            (:class:`~subtask_opt.tour.constraints.TourConstraints`); default a
            closed tour from the problem's ``first``. Open paths and homes are
            matrix transforms of the closed tour; precedence and a fixed end use
            the pinned-permutation GA (:mod:`subtask_opt.tour.precedence`); with
            a clustered problem, its pinned clustered kind
            (:mod:`subtask_opt.tour.pinned_clustered`), which chooses every
            cluster's node exactly during the search (the bound is the one of the
            relaxation without precedence, so it stays valid).
    """
    from subtask_opt.tour.lazy import LazyLegsProblem, solve_lazy

    if not isinstance(problem, (MatrixProblem, ClusteredProblem, GtspProblem,
                                LazyLegsProblem)):
        raise ParameterError(f"solve needs a MatrixProblem, ClusteredProblem, GtspProblem, "
                             f"LazyLegsProblem or ArmProblem, "
                             f"got {type(problem).__name__}")
    check_seed(seed)
    if params is None:
        params = SolverParams()
    elif not isinstance(params, SolverParams):
        raise ParameterError(f"solve: params must be a SolverParams, got {params!r}")
    require_in_range("solve", "certify_time_limit", certify_time_limit, 1e-3, 86_400.0)
    if isinstance(problem, LazyLegsProblem):
        return solve_lazy(problem, seed=int(seed), stop=stop, params=params,
                          constraints=constraints, progress=progress, certify=certify,
                          certify_time_limit=certify_time_limit)
    cons, problem, canon = _shaped(problem, constraints)
    if params.kicks is not None and canon.needs_pins:
        raise ParameterError("SolverParams.kicks applies to tours without precedence or a "
                             "fixed end (the pinned search has no kicks)")
    configured = isinstance(problem, (ClusteredProblem, GtspProblem))
    criteria = as_criteria(stop, params.default_stop(problem.size, configured=configured))
    runs = params.default_runs(problem.size, configured=configured)
    matrix = problem.matrix
    n = problem.size
    paper = params.preset == "paper"
    tensor = None
    data: np.ndarray | ConfiguredData | PinnedClusteredData
    cdata = None
    if configured:
        from subtask_opt.tour.configurations import pack_data

        search = SEARCH_PAPER if paper else SEARCH_FAST
        if isinstance(problem, GtspProblem):
            cdata = (problem.open_data(canon.first, canon.last) if canon.open_path
                     else problem.configured_data())
            data = cdata = cdata._replace(search=search)
        elif canon.open_path:
            assert isinstance(problem, ClusteredProblem)
            tensor = transform_tensor(problem.costs, canon)
            data = pack_data(tensor)[0]._replace(search=search)
        else:
            assert isinstance(problem, ClusteredProblem)
            data = problem.configured_data()._replace(search=search)
        dist = data.dist
        kind = Kind.CONFIGURED_PERMUTATION
        neighbours = neighbour_table(dist, params.neighbours)
    else:
        # a GA tour may not use an excluded leg: a finite penalty keeps the costs comparable
        cm = canon.matrix
        data = np.where(np.isfinite(cm), cm, penalty_for(cm))
        dist = data
        # the paper's search keeps its nearest lists
        neighbours = (neighbour_table if paper else candidate_table)(cm, params.neighbours)
        kind = Kind.PERMUTATION
        if paper:
            search = SEARCH_PAPER
        else:
            # a home keeps the costs; an open path's free return makes them asymmetric
            symmetric = problem.symmetric and not canon.open_path
            search = SEARCH_FAST if symmetric else SEARCH_EXACT
    if canon.needs_pins:
        # precedence or a fixed end: operators that keep both (tour/precedence.py); with
        # clusters the nodes are chosen exactly during the search (tour/pinned_clustered.py)
        if isinstance(data, ConfiguredData):
            data = make_data(data.dist, data, lns=data.lns)
            kind = Kind.PINNED_CLUSTERED
        else:
            data = np.ascontiguousarray(dist)
            kind = Kind.PINNED_PERMUTATION
        if stop is None and not paper:
            # precedence makes local optima deeper (fewer moves are feasible): a longer stall
            criteria = [NoImprovement(max(PINNED_STALL, n // 2)), MaxGenerations(50_000)]
    bound = None
    if n <= params.bound_max_nodes:
        # every leg costs at least dist (the cheapest configuration pair), so a
        # bound of that matrix bounds the tour; a tour that meets it is proven optimal
        bound = _relaxation_bound(problem, canon, dist)
        if stop is None:
            criteria = [*criteria, TargetCost(bound * (1 + 1e-12) + 1e-12)]
    aux: PinnedAux | PermutationAux
    if kind == Kind.PINNED_PERMUTATION:
        aux = make_pinned_aux(n, canon.first, canon.last, canon.pairs)
    elif kind == Kind.PINNED_CLUSTERED:
        aux = make_pinned_clustered_aux(n, canon.first, canon.last, canon.pairs)
    else:
        aux = make_aux(neighbours, nearest_fallback=not paper,
                       grasp_share=params.grasp_share, max_segment=params.max_segment,
                       neighbours=params.neighbours, search=search, kicks=params.kicks)
    config = GAConfig(population=params.population, elite=1, crossover_rate=1.0,
                      mutation_rate=0.0, restart_on_convergence=True,
                      convergence_tol=params.convergence_tol)
    if paper:
        config = params.paper_loop or replace(PAPER_LOOP, population=params.population)
    total = next((c.generations for c in criteria if isinstance(c, MaxGenerations)), None)
    with progress_bar(progress, total=total, desc="micro-GA", unit="gen") as bar:
        done = [0]

        def on_chunk(p: Progress) -> None:
            bar.update(p.generation - done[0])
            done[0] = p.generation
            bar.set_postfix_str(f"best {p.best_cost:.4f}")

        outcome = run_ga(use(kind), config, data, aux, max_genes=n, seed=int(seed),
                         criteria=criteria, on_chunk=on_chunk, runs=runs)
    tour = _rotate(outcome.genes, canon.first)
    configs = None
    if isinstance(problem, GtspProblem):
        assert cdata is not None
        vertices = problem.decode(tour, cdata)[1]
        configs = np.empty(n, dtype=np.int64)
        configs[tour] = vertices
        matrix = problem.weights[np.ix_(configs, configs)].copy()
        np.fill_diagonal(matrix, 0.0)
        matrix.setflags(write=False)
    elif configured:
        assert isinstance(problem, ClusteredProblem)
        from subtask_opt.tour.configurations import best_configurations, induced_matrix

        configs = best_configurations(tour, problem.costs if tensor is None else tensor)[1]
        matrix = induced_matrix(problem.costs, configs)
        matrix.setflags(write=False)
    legs = canon.user_legs(matrix, tour)
    if not np.all(np.isfinite(legs)):
        k = int(np.flatnonzero(~np.isfinite(legs))[0])
        raise NoPathError(
            f"no tour avoids the impossible legs (the best one needs the impossible leg "
            f"{tour[k]} -> {tour[(k + 1) % n]})")
    broken = canon.violations(tour)
    if broken:  # the operators keep every constraint: this is a bug, never an answer
        raise SubtaskOptError(f"internal error: the answer breaks its constraints: {broken}")
    total_time = float(np.sum(legs))
    certified = None
    if certify:
        certified = _certify(problem, canon, total_time, certify_time_limit, tour,
                             configs if configured else None)
    return Result(
        order=canon.user_order(tour),
        total_time=total_time,
        leg_times=legs,
        matrix=matrix,
        generations=outcome.generations,
        restarts=outcome.restarts,
        runtime_s=outcome.runtime_s,
        seed=int(seed),
        history=outcome.history,
        preset=params.preset,
        lower_bound=bound,
        certified=certified,
        constraints=cons,
        start=None if canon.home >= 0 else canon.first,
        runs=outcome.runs,
        configurations=configs,
    )



def check_seed(seed: object) -> int:
    """``seed`` as an int, or a :class:`ParameterError` naming it and the range."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not (
            0 <= seed < 2**63):
        raise ParameterError(f"seed must be an integer in [0, 2**63), got {seed!r}")
    return int(seed)


def _relaxation_bound(problem: TourProblem, canon: Canonical,
                      costs: np.ndarray) -> float:
    """A lower bound of the constrained problem: a bound of a relaxation without precedence.

    ``costs`` are the canonical costs the GA sees. An open path over symmetric
    costs is bounded through :func:`~subtask_opt.tour.constraints.symmetric_path_matrix`
    (far tighter than the asymmetric bound of its zero-cost return); everything
    else by the bound of ``costs``.
    """
    if canon.open_path and problem.symmetric:
        base = np.array(costs, dtype=float)
        if canon.last >= 0:
            base[canon.last, canon.first] = base[canon.first, canon.last]
        else:
            base[:, canon.first] = base[canon.first, :]
        if np.allclose(base, base.T, rtol=1e-12, atol=0.0):
            m, offset = symmetric_path_matrix(base, canon.first,
                                              None if canon.last < 0 else canon.last)
            return max(0.0, lower_bound(m, seed=0) - offset)
    return lower_bound(costs, seed=0)


def _shaped(problem: TourProblem, constraints: TourConstraints | None,
            ) -> tuple[TourConstraints, TourProblem, Canonical]:
    """The validated constraints, the problem and its canonical form
    (:func:`subtask_opt.tour.constraints.canonical`)."""
    first = problem.first
    constraints = checked(constraints, first)
    constraints.check_size(problem.size, matrix_home=True)
    if first is not None and constraints.start is not None and first != constraints.start:
        raise ParameterError(f"the problem's first={first} and the constraints' "
                             f"start={constraints.start} contradict each other")
    canon = canonical(problem.matrix, constraints, default_start=first or 0)
    return constraints, problem, canon


def _certify(problem: TourProblem, canon: Canonical, total: float,
             time_limit: float, tour: np.ndarray, configs: np.ndarray | None) -> str:
    """Prove ``total`` optimal with an exact method, or say why not.

    Chosen configurations (``configs``): the generalised-TSP branch and cut
    (:func:`~subtask_opt.tour.exact.gtsp_optimum`, this answer as its incumbent) for a
    closed tour without precedence, else the arc MILP with cluster positions
    (:func:`~subtask_opt.tour.exact.milp_pinned_clustered`; small problems). Fixed
    configurations: a symmetric closed tour uses the subtour-cut MILP; anything else
    (asymmetric costs, an open path, a home, precedence) the MTZ MILP of the canonical form.
    """
    from subtask_opt.tour.exact import milp_optimum, milp_pinned

    try:
        if configs is not None:
            if canon.open_path or canon.needs_pins:
                optimum = _pinned_clustered_optimum(problem, canon, time_limit)
            elif isinstance(problem, GtspProblem):
                from subtask_opt.tour.exact import gtsp_set_optimum

                optimum = gtsp_set_optimum(problem, incumbent=configs[tour],
                                           time_limit=time_limit)[0]
            else:
                assert isinstance(problem, ClusteredProblem)
                optimum = proven_configured_optimum(problem, tour, configs, time_limit)
        elif canon.open_path and not canon.pairs.size and problem.symmetric:
            m, offset = symmetric_path_matrix(problem.matrix, canon.first,
                                              None if canon.last < 0 else canon.last)
            optimum = milp_optimum(m, time_limit=time_limit)[0] - offset
        elif canon.needs_pins or canon.open_path or not problem.symmetric:
            if not np.all(np.isfinite(canon.matrix)):
                return "not certified: the MTZ MILP needs finite travel times"
            optimum, _ = milp_pinned(canon.matrix, canon.first, canon.last, canon.pairs,
                                     time_limit=time_limit)
        else:
            optimum, _ = milp_optimum(problem.matrix, time_limit=time_limit)
    except SubtaskOptError as exc:
        return f"not certified: {exc}"
    if total <= optimum * (1 + 1e-9) + 1e-12:
        return "optimal (proven)"
    excess = 100 * (total / optimum - 1)
    return f"not optimal: the proven optimum is {optimum:.6g} ({excess:.4f}% less)"


def _pinned_clustered_optimum(problem: TourProblem, canon: Canonical,
                              time_limit: float) -> float:
    """The proven optimum of a clustered problem's canonical form (pins, precedence, an
    open path's free return) by the arc MILP over every node
    (:func:`~subtask_opt.tour.exact.milp_pinned_clustered`)."""
    from subtask_opt.tour.exact import milp_pinned_clustered

    if isinstance(problem, GtspProblem):
        w = np.array(problem.weights, dtype=float)
        clusters = np.asarray(problem.sets, dtype=np.int64)
        if canon.open_path:
            into = clusters == canon.first
            rows = slice(None) if canon.last < 0 else clusters == canon.last
            w[np.ix_(np.arange(len(w))[rows], np.flatnonzero(into))] = 0.0
    else:
        assert isinstance(problem, ClusteredProblem)
        t = transform_tensor(problem.costs, canon)
        t[~problem.present] = np.inf  # absent nodes: no arc out ...
        t[:, :, ~problem.present] = np.inf  # ... and none in
        n, k = t.shape[:2]
        w = t.reshape(n * k, n * k)
        clusters = np.repeat(np.arange(n), k)
    return milp_pinned_clustered(w, clusters, canon.first, canon.last, canon.pairs,
                                 time_limit=time_limit)[0]


def proven_configured_optimum(problem: ClusteredProblem, tour: np.ndarray,
                              configs: np.ndarray, time_limit: float) -> float:
    """The proven optimum of a closed tour over orders and configurations (the
    generalised TSP of a problem that chooses configurations), by
    :func:`~subtask_opt.tour.exact.gtsp_optimum` with ``tour`` at ``configs`` (per subtask)
    as its incumbent, which only speeds the proof up.

    Raises:
        SubtaskOptError: not proven within ``time_limit`` seconds, or leg times that are
            not finite and symmetric between the reachable configurations.
    """
    from subtask_opt.tour.configurations import configuration_graph
    from subtask_opt.tour.exact import gtsp_optimum

    cost, subtask, configuration = configuration_graph(problem.costs, problem.present)
    if not np.all(np.isfinite(cost)) or not np.allclose(cost, cost.T, rtol=1e-9, atol=1e-12):
        raise SubtaskOptError("the generalised-TSP certificate needs finite, symmetric "
                              "leg times between the configurations")
    node = {(int(i), int(c)): v for v, (i, c) in
            enumerate(zip(subtask.tolist(), configuration.tolist(), strict=True))}
    incumbent = [node[(int(i), int(configs[i]))] for i in tour]
    return gtsp_optimum(cost, subtask, incumbent=incumbent, time_limit=time_limit)[0]


def _rotate(tour: np.ndarray, first: int) -> np.ndarray:
    start = int(np.flatnonzero(tour == first)[0])
    return np.roll(np.asarray(tour, dtype=np.int64), -start)


PINNED_STALL = 60
"""Default stall (generations without improvement) of searches with precedence or a
fixed end; 15 missed the optimum of 1 in 200 random small constrained instances."""

