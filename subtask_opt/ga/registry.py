"""The chromosome types the GA loop knows, and the dispatch to their operators.

Numba caches a compiled function by its argument types; a loop that takes its
operators as function arguments cannot be cached reliably across processes
(numba pickles references to the functions), and pays for passing them on
every call. So each chromosome type has an integer ``kind``, and five small
dispatch functions call the right operator for it. Adding a chromosome type
means writing its five operators (signatures in :mod:`subtask_opt.ga.core`)
and one branch in each dispatch function below.
"""

from __future__ import annotations

from dataclasses import dataclass

from numba import njit

from ..errors import ParameterError
from . import configured as gtsp
from . import permutation as tsp
from . import waypoints as wp

PAPER_TSP = 0
MEMETIC_TSP = 1
EXACT_MEMETIC_TSP = 2
WAYPOINT_PATH = 3
PAPER_CONFIGURED_TSP = 4
MEMETIC_CONFIGURED_TSP = 5
_NAMES = {
    PAPER_TSP: "paper micro-GA (TSP)",
    MEMETIC_TSP: "micro-GA + fast local search (symmetric TSP)",
    EXACT_MEMETIC_TSP: "micro-GA + exact local search (any TSP)",
    WAYPOINT_PATH: "waypoint path on a grid (GA path planner)",
    PAPER_CONFIGURED_TSP: "paper micro-GA, exact decoding of elbow configurations",
    MEMETIC_CONFIGURED_TSP: "micro-GA + local search, exact decoding of elbow configurations",
}


@dataclass(frozen=True)
class OperatorSet:
    """A registered chromosome type: what :func:`subtask_opt.ga.core.run_ga` runs."""

    kind: int

    def __post_init__(self) -> None:
        if self.kind not in _NAMES:
            raise ParameterError(f"OperatorSet.kind must be one of {sorted(_NAMES)}, "
                                 f"got {self.kind!r}")

    @property
    def name(self) -> str:
        return _NAMES[self.kind]


PAPER_OPERATORS = OperatorSet(PAPER_TSP)
"""The paper's micro-GA: random restarts, greedy crossover (random fallback), nothing else."""

MEMETIC_OPERATORS = OperatorSet(MEMETIC_TSP)
"""Our default for symmetric costs: greedy crossover (nearest fallback) and restarts
(kicks of the best tour or randomised nearest-neighbour tours), each followed by a
fast 2-opt/Or-opt local search around what changed."""

EXACT_MEMETIC_OPERATORS = OperatorSet(EXACT_MEMETIC_TSP)
"""The default's counterpart for asymmetric costs: full-sweep exact local search."""

WAYPOINT_OPERATORS = OperatorSet(WAYPOINT_PATH)
"""Variable-length waypoint paths of the GA path planner (:mod:`subtask_opt.ga.waypoints`)."""

PAPER_CONFIGURED_OPERATORS = OperatorSet(PAPER_CONFIGURED_TSP)
"""The paper's micro-GA on orders whose elbow configurations are decoded exactly
(:mod:`subtask_opt.ga.configured`)."""

MEMETIC_CONFIGURED_OPERATORS = OperatorSet(MEMETIC_CONFIGURED_TSP)
"""Our default on orders with exactly decoded elbow configurations: greedy crossover
and restarts on the cheapest leg times, then alternating decoding and local search."""


@njit(cache=True)
def randomize(kind, genes, data, aux, rng, best, best_len):
    if kind == WAYPOINT_PATH:
        return wp.random_path(genes, data, aux, rng, best, best_len)
    if kind == MEMETIC_TSP:
        return tsp.kicked_best_polished(genes, data, aux, rng, best, best_len)
    if kind == EXACT_MEMETIC_TSP or kind == MEMETIC_CONFIGURED_TSP:
        return tsp.kicked_best(genes, data, aux, rng, best, best_len)
    return tsp.random_tour(genes, data, aux, rng, best, best_len)


@njit(cache=True)
def evaluate(kind, genes, length, data, aux):
    if kind == WAYPOINT_PATH:
        return wp.path_cost(genes, length, data, aux)
    if kind == PAPER_CONFIGURED_TSP or kind == MEMETIC_CONFIGURED_TSP:
        return gtsp.tour_cost(genes, length, data, aux)
    return tsp.tour_cost(genes, length, data, aux)


@njit(cache=True)
def crossover(kind, genes_a, len_a, genes_b, len_b, data, aux, rng, child):
    if kind == WAYPOINT_PATH:
        return wp.one_point_crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child)
    if kind == MEMETIC_TSP:
        return tsp.greedy_crossover_polished(genes_a, len_a, genes_b, len_b, data, aux, rng,
                                             child)
    return tsp.greedy_crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child)


@njit(cache=True)
def mutate(kind, genes, length, data, aux, rng, strength):
    if kind == WAYPOINT_PATH:
        return wp.nonuniform_mutation(genes, length, data, aux, rng, strength)
    return length


@njit(cache=True)
def improve(kind, genes, length, data, aux):
    if kind == WAYPOINT_PATH:
        return wp.shortcut(genes, length, data, aux)
    if kind == EXACT_MEMETIC_TSP:
        return tsp.exact_local_search(genes, length, data, aux)
    if kind == MEMETIC_CONFIGURED_TSP:
        return gtsp.local_search(genes, length, data, aux)
    return length
