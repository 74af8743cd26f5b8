"""Stopping criteria for the GA core and the other iterative optimisers.

Each criterion is a small callable ``criterion(progress) -> bool``; a run stops
as soon as any of its criteria says so (PyVRP's ``pyvrp.stop`` style). Because a
numba kernel cannot call Python objects, the driver runs the kernel in chunks:
:meth:`generations_left` tells the driver how far it may run before asking
again, so generation-based criteria stop at exactly the same generation
whatever the chunking, and a seeded run is reproducible.
"""

from __future__ import annotations

import contextvars
import math
import numbers
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from subtask_opt.base.errors import (
    ParameterError,
    TimeLimitReached,
    require_int,
    require_non_negative,
    require_positive,
)

_LIMIT: contextvars.ContextVar[tuple[float, float] | None] = contextvars.ContextVar(
    "time_limit", default=None)  # (monotonic deadline, seconds)


@contextmanager
def time_limit(seconds: float | None, *, started: float | None = None) -> Iterator[None]:
    """Work inside the block that asks :func:`check_time_limit` (building an arm problem:
    IK, collision checks, leg times) stops with :class:`TimeLimitReached` once ``seconds``
    of wall time have passed since ``started`` (a ``time.monotonic()`` reading; None: the
    block's start); ``seconds`` None: no limit. The CLI's ``--time-limit`` wraps the
    problem's construction in it (the search has its own :class:`MaxRuntime`, from what is
    left)."""
    if seconds is None:
        yield
        return
    require_positive("time_limit", "seconds", seconds)
    begin = time.monotonic() if started is None else float(started)
    token = _LIMIT.set((begin + float(seconds), float(seconds)))
    try:
        yield
    finally:
        _LIMIT.reset(token)


def check_time_limit(doing: str) -> None:
    """Raise :class:`TimeLimitReached` naming ``doing`` (what the work was about to do or
    was doing) if the enclosing :func:`time_limit` has run out."""
    limit = _LIMIT.get()
    if limit is not None and time.monotonic() >= limit[0]:
        raise TimeLimitReached(f"the time limit of {limit[1]:g} s ran out {doing}")


@dataclass(frozen=True)
class Progress:
    """What a stopping criterion may look at between chunks of generations."""

    generation: int
    best_cost: float
    generations_without_improvement: int
    runtime_s: float


@runtime_checkable
class StoppingCriterion(Protocol):
    def __call__(self, progress: Progress) -> bool: ...

    def generations_left(self, progress: Progress) -> int | None:
        """Generations that may run before this criterion must be asked again.

        ``None`` means the criterion does not bound the chunk (time-based ones).
        """
        ...


@dataclass(frozen=True)
class MaxGenerations:
    """Stop after ``generations`` generations in total."""

    generations: int

    def __post_init__(self) -> None:
        require_int("MaxGenerations", "generations", self.generations, 1)

    def __call__(self, progress: Progress) -> bool:
        return progress.generation >= self.generations

    def generations_left(self, progress: Progress) -> int | None:
        return max(self.generations - progress.generation, 0)


@dataclass(frozen=True)
class MaxRuntime:
    """Stop once ``seconds`` of wall time have passed (checked between chunks)."""

    seconds: float

    def __post_init__(self) -> None:
        require_positive("MaxRuntime", "seconds", self.seconds)

    def __call__(self, progress: Progress) -> bool:
        return progress.runtime_s >= self.seconds

    def generations_left(self, progress: Progress) -> int | None:
        return None


@dataclass(frozen=True)
class NoImprovement:
    """Stop after ``generations`` consecutive generations without a better best."""

    generations: int

    def __post_init__(self) -> None:
        require_int("NoImprovement", "generations", self.generations, 1)

    def __call__(self, progress: Progress) -> bool:
        return progress.generations_without_improvement >= self.generations

    def generations_left(self, progress: Progress) -> int | None:
        return max(self.generations - progress.generations_without_improvement, 0)


@dataclass(frozen=True)
class TargetCost:
    """Stop as soon as the best cost is at most ``cost`` (plus a relative ``tolerance``)."""

    cost: float
    tolerance: float = 1e-9

    def __post_init__(self) -> None:
        if (isinstance(self.cost, bool) or not isinstance(self.cost, numbers.Real)
                or not math.isfinite(self.cost)):
            raise ParameterError(f"TargetCost.cost must be a finite number, got {self.cost!r}")
        require_non_negative("TargetCost", "tolerance", self.tolerance)

    @property
    def threshold(self) -> float:
        return self.cost + self.tolerance * abs(self.cost)

    def __call__(self, progress: Progress) -> bool:
        return progress.best_cost <= self.threshold

    def generations_left(self, progress: Progress) -> int | None:
        return None


def as_criteria(stop: StoppingCriterion | list[StoppingCriterion] | tuple | None,
                default: list[StoppingCriterion]) -> list[StoppingCriterion]:
    """Normalise ``stop`` (one criterion, a sequence, or None) to a non-empty list."""
    if stop is None:
        return list(default)
    criteria = list(stop) if isinstance(stop, (list, tuple)) else [stop]
    if not criteria:
        raise ParameterError("stop must hold at least one stopping criterion, got []")
    for c in criteria:  # duck-typed: isinstance on a runtime Protocol is slow
        if not (callable(c) and callable(getattr(c, "generations_left", None))):
            raise ParameterError(f"stop: {c!r} is not a stopping criterion")
    if not any(c.generations_left(Progress(0, math.inf, 0, 0.0)) is not None
               or isinstance(c, MaxRuntime) for c in criteria):
        raise ParameterError(
            "stop: a TargetCost alone may never be met; add MaxGenerations, "
            "NoImprovement or MaxRuntime")
    return criteria


def target_threshold(criteria: list[StoppingCriterion]) -> float:
    """The lowest TargetCost threshold among ``criteria`` (``-inf`` when none)."""
    thresholds = [c.threshold for c in criteria if isinstance(c, TargetCost)]
    return min(thresholds) if thresholds else -math.inf


def kernel_limits(criteria: list[StoppingCriterion]) -> tuple[int, float]:
    """``(stall_limit, target)`` for a kernel that enforces them itself.

    The stall limit is the smallest NoImprovement (a huge number when none),
    the target the lowest TargetCost threshold (``-inf`` when none).
    """
    stall = min((c.generations for c in criteria if isinstance(c, NoImprovement)),
                default=2**62)
    return stall, target_threshold(criteria)
