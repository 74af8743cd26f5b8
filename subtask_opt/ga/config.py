"""How the GA loop breeds: :class:`GAConfig`, the one validator of GA parameters."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

from subtask_opt.base.errors import (
    ParameterError,
    require_in_range,
    require_int,
    require_non_negative,
)

# Readings of the sequencing paper's micro-GA (see GAConfig); the kernel reads the index.
PAIRINGS = ("random", "shuffle", "rest", "double")
CONVERGENCE_TESTS = ("cost", "edges", "adjacency")
CROSSOVER_STARTS = ("parent", "random", "first")


class LoopParams(NamedTuple):
    """:class:`GAConfig` as the loop kernel reads it (numba caches NamedTuple arguments)."""

    elite: int
    crossover_rate: float
    mutation_rate: float
    restart_on_convergence: bool
    convergence_tol: float
    tournament: int
    mutation_horizon: float
    pairing: int = 0
    convergence: int = 0
    crossover_start: int = 0
    distinct_mates: bool = False


@dataclass(frozen=True)
class GAConfig:
    """How the loop breeds.

    Attributes:
        population: number of individuals (5 for the micro-GA).
        elite: how many of the best pass unchanged to the next generation.
        crossover_rate: probability that a child comes from crossover rather
            than as a copy of its first parent.
        mutation_rate: probability that a child is mutated.
        restart_on_convergence: re-seed (best + fresh individuals) once the
            population has converged.
        convergence_tol: the population has converged when
            ``max(cost) - min(cost) <= convergence_tol * |min(cost)|``, or when
            its sorted costs are the same as in the previous generation.
        tournament: 0 picks each parent pair uniformly at random among
            distinct individuals; k >= 2 picks each parent by a k-tournament.
        mutation_horizon: generations over which non-uniform mutation shrinks
            (its ``strength`` argument is generation / horizon, capped at 1).
        pairing: how the non-elite children get their parents: ``"random"``
            (each child an independent pair, see ``tournament``), ``"shuffle"``
            (all strings in a random order, each mated with the next, cyclically),
            ``"rest"`` (the same over the non-elite strings only) or ``"double"``
            (twice as many random pairs as children; the better half of the children
            is kept).
        convergence: ``"cost"`` (the test above), ``"edges"`` (closed tours
            only: at most ``convergence_tol`` of the other strings' edges, either
            direction, are not in the best string) or ``"adjacency"`` (the same
            over the directed successor entries: Krishnakumar's bit test read
            literally on the paper's adjacency strings); with either, a population
            whose sorted costs did not change has converged too.
        crossover_start: (permutations only) the city a crossover child starts
            at: ``"parent"`` (the first city of either parent, as the operator
            does), ``"random"`` (any city) or ``"first"`` (always city 0, the first
            entry of an adjacency string).
        distinct_mates: mates must also differ in content, not only in index
            (a second parent identical to the first is replaced by a random string
            that differs; identical strings still mate when the population holds
            nothing else).
    """

    population: int = 5
    elite: int = 1
    crossover_rate: float = 1.0
    mutation_rate: float = 0.0
    restart_on_convergence: bool = True
    convergence_tol: float = 0.01
    tournament: int = 0
    mutation_horizon: int = 100
    pairing: str = "random"
    convergence: str = "cost"
    crossover_start: str = "parent"
    distinct_mates: bool = False

    def __post_init__(self) -> None:
        self.validate(type(self).__name__)

    def validate(self, owner: str) -> None:
        """Check every field; ``owner`` names the parameter class in messages
        (planner parameter classes that embed these fields validate through here)."""
        require_int(owner, "population", self.population, 2, 100_000)
        require_int(owner, "elite", self.elite, 0)
        if self.elite >= self.population:
            raise ParameterError(
                f"{owner}.elite must be < population ({self.population}), got {self.elite!r}")
        require_in_range(owner, "crossover_rate", self.crossover_rate, 0.0, 1.0)
        require_in_range(owner, "mutation_rate", self.mutation_rate, 0.0, 1.0)
        require_non_negative(owner, "convergence_tol", self.convergence_tol)
        if not isinstance(self.restart_on_convergence, bool):
            raise ParameterError(f"{owner}.restart_on_convergence must be True or False, "
                                 f"got {self.restart_on_convergence!r}")
        require_int(owner, "tournament", self.tournament, 0)
        if self.tournament == 1 or self.tournament > self.population:
            raise ParameterError(
                f"{owner}.tournament must be 0 or in [2, population], got {self.tournament!r}")
        require_int(owner, "mutation_horizon", self.mutation_horizon, 1, 2**62)
        # the paper readings; a planner class that embeds the GA fields may lack them
        for name, choices in (("pairing", PAIRINGS), ("convergence", CONVERGENCE_TESTS),
                              ("crossover_start", CROSSOVER_STARTS)):
            value = getattr(self, name, choices[0])
            if value not in choices:
                raise ParameterError(f"{owner}.{name} must be one of {', '.join(choices)}, "
                                     f"got {value!r}")
        if not isinstance(getattr(self, "distinct_mates", False), bool):
            raise ParameterError(f"{owner}.distinct_mates must be True or False, "
                                 f"got {self.distinct_mates!r}")

    def loop_params(self) -> LoopParams:
        """The kernel's view of this configuration."""
        return LoopParams(int(self.elite), float(self.crossover_rate), float(self.mutation_rate),
                          bool(self.restart_on_convergence), float(self.convergence_tol),
                          int(self.tournament), float(self.mutation_horizon),
                          PAIRINGS.index(self.pairing),
                          CONVERGENCE_TESTS.index(self.convergence),
                          CROSSOVER_STARTS.index(self.crossover_start),
                          bool(self.distinct_mates))
