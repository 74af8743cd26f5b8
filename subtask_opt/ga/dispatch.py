"""The one composition root of the GA: chromosome kind -> its five operators.

numba compiles a function that takes other numba functions as arguments once per
function object and cannot cache it across processes (only explicit first-class
``FunctionType`` arguments can be cached, and they shorten the cold start little:
CONTRIBUTING), so the loop (:func:`subtask_opt.ga.loop.evolve`) takes a
kind *tag* instead (:func:`subtask_opt.ga.kinds.tag`), whose numba type
differs per kind. The five functions below are resolved per kind *while numba compiles*
(``numba.extending.overload``): the loop compiled for one kind contains that
kind's operators only, so a run compiles just what it needs, and a kind that
was never registered is a clear typing error rather than a silent fallback.

Operator signatures (``data``, ``aux`` belong to the operators):

``randomize(genes_out, data, aux, rng, best, best_len) -> length``
    A new individual for the initial population (``best_len == 0``) and for a
    restart (``best`` holds the best so far, which a restart may perturb).
``evaluate(genes, length, data, aux) -> cost``
    Cost to minimise (``inf`` for an infeasible individual).
``crossover(genes_a, len_a, genes_b, len_b, data, aux, rng, child) -> length``
    Writes one child into ``child``.
``mutate(genes, length, data, aux, rng, strength) -> length``
    In place; ``strength`` = generation / horizon, in [0, 1].
``improve(genes, length, data, aux) -> length``
    In-place local search (the identity for a plain GA).

No kind is registered here, nor at the import of the module that defines it: every
kind's operators are registered in one place, :mod:`subtask_opt.chromosomes`, when a
caller asks for the kind (``run_ga(use(Kind.X), ...)``), so nothing under
:mod:`subtask_opt.ga` imports a tour, a robot or a map.
"""

from __future__ import annotations

from typing import Any, NamedTuple

from numba.core.errors import TypingError
from numba.extending import overload

from subtask_opt.base.errors import ParameterError
from subtask_opt.ga.kinds import TAGS, Kind

OPERATOR_NAMES = ("randomize", "evaluate", "crossover", "mutate", "improve")


class OperatorSet(NamedTuple):
    """The five numba operators of one chromosome type."""

    randomize: Any
    evaluate: Any
    crossover: Any
    mutate: Any
    improve: Any


_REGISTRY: dict[int, OperatorSet] = {}


def register(kind: Kind, operators: OperatorSet) -> None:
    """Make ``operators`` the chromosome type ``kind`` (:func:`subtask_opt.chromosomes.use`)."""
    if not isinstance(kind, Kind):
        raise ParameterError(f"register: kind must be a Kind, got {kind!r}")
    missing = [n for n in OPERATOR_NAMES if not callable(getattr(operators, n, None))]
    if missing:
        raise ParameterError(f"register: {kind.name} lacks the operators {missing}")
    _REGISTRY[int(kind)] = operators


def registered(kind: Kind) -> OperatorSet | None:
    """The operators registered for ``kind``, or None."""
    return _REGISTRY.get(int(kind))


_KIND_OF_TAG = {cls: kind for kind, cls in TAGS.items()}


def _operator(kind: Any, name: str) -> Any:
    cls = getattr(kind, "instance_class", None)
    if cls not in _KIND_OF_TAG:
        raise TypingError(f"GA dispatch: expected a kind tag (subtask_opt.ga.kinds.tag), "
                          f"got {kind}")
    ops = _REGISTRY.get(int(_KIND_OF_TAG[cls]))
    if ops is None:
        raise TypingError(f"GA dispatch: no operators registered for {_KIND_OF_TAG[cls]!r}")
    return getattr(ops, name)


def _python_operator(kind: Any, name: str) -> Any:
    """The operator for a kind tag in plain Python (numba compiles the overloads instead)."""
    ops = _REGISTRY.get(int(_KIND_OF_TAG[type(kind)]))
    if ops is None:
        raise ParameterError(f"GA dispatch: no operators registered for {type(kind).__name__}")
    return getattr(ops, name)


def randomize(kind, genes, data, aux, rng, best, best_len):  # type: ignore[no-untyped-def]
    """Dispatch to the kind's randomize (Python body: used only with NUMBA_DISABLE_JIT)."""
    return _python_operator(kind, "randomize")(genes, data, aux, rng, best, best_len)


def evaluate(kind, genes, length, data, aux):  # type: ignore[no-untyped-def]
    """Dispatch to the kind's evaluate (Python body: used only with NUMBA_DISABLE_JIT)."""
    return _python_operator(kind, "evaluate")(genes, length, data, aux)


def crossover(kind, genes_a, len_a, genes_b, len_b, data, aux, rng, child):  # type: ignore[no-untyped-def]
    """Dispatch to the kind's crossover (Python body: used only with NUMBA_DISABLE_JIT)."""
    op = _python_operator(kind, "crossover")
    return op(genes_a, len_a, genes_b, len_b, data, aux, rng, child)


def mutate(kind, genes, length, data, aux, rng, strength):  # type: ignore[no-untyped-def]
    """Dispatch to the kind's mutate (Python body: used only with NUMBA_DISABLE_JIT)."""
    return _python_operator(kind, "mutate")(genes, length, data, aux, rng, strength)


def improve(kind, genes, length, data, aux):  # type: ignore[no-untyped-def]
    """Dispatch to the kind's improve (Python body: used only with NUMBA_DISABLE_JIT)."""
    return _python_operator(kind, "improve")(genes, length, data, aux)


@overload(randomize)
def _randomize(kind, genes, data, aux, rng, best, best_len):  # type: ignore[no-untyped-def]
    op = _operator(kind, "randomize")

    def impl(kind, genes, data, aux, rng, best, best_len):  # type: ignore[no-untyped-def]
        return op(genes, data, aux, rng, best, best_len)
    return impl


@overload(evaluate)
def _evaluate(kind, genes, length, data, aux):  # type: ignore[no-untyped-def]
    op = _operator(kind, "evaluate")

    def impl(kind, genes, length, data, aux):  # type: ignore[no-untyped-def]
        return op(genes, length, data, aux)
    return impl


@overload(crossover)
def _crossover(kind, genes_a, len_a, genes_b, len_b, data, aux, rng, child):  # type: ignore[no-untyped-def]
    op = _operator(kind, "crossover")

    def impl(kind, genes_a, len_a, genes_b, len_b, data, aux, rng, child):  # type: ignore[no-untyped-def]
        return op(genes_a, len_a, genes_b, len_b, data, aux, rng, child)
    return impl


@overload(mutate)
def _mutate(kind, genes, length, data, aux, rng, strength):  # type: ignore[no-untyped-def]
    op = _operator(kind, "mutate")

    def impl(kind, genes, length, data, aux, rng, strength):  # type: ignore[no-untyped-def]
        return op(genes, length, data, aux, rng, strength)
    return impl


@overload(improve)
def _improve(kind, genes, length, data, aux):  # type: ignore[no-untyped-def]
    op = _operator(kind, "improve")

    def impl(kind, genes, length, data, aux):  # type: ignore[no-untyped-def]
        return op(genes, length, data, aux)
    return impl
