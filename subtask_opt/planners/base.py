"""The planner protocol, the registry of planners by family and name, and the shared outcomes.

Every planner is a function

    plan(world, start, goal, *, params=None, seed=None, stop=None) -> PlanResult

``params`` is the planner's own frozen parameter dataclass (None: defaults);
``seed`` is required to be None or an integer in [0, 2**63) and is used by
stochastic planners only; ``stop`` (a stopping criterion or a list) is honoured
by iterative planners (GA, PSO) and must be None for the others. A planner
that fails returns ``success=False`` with its :class:`Outcome` and a reason; it
never returns None and never loops forever.

Planners register themselves with :func:`register` when their module is
imported; :func:`planners` imports a family's modules and lists them, so the
CLI's choices, help texts and comparison tables all come from here.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from subtask_opt.base.errors import ParameterError
from subtask_opt.base.results import Outcome, PlanResult

FAMILIES: dict[str, tuple[str, ...]] = {
    "grid": ("subtask_opt.planners.grid.distance_transform", "subtask_opt.planners.grid.ga_path",
             "subtask_opt.planners.grid.vff", "subtask_opt.planners.grid.vfh"),
    "polygon": ("subtask_opt.planners.polygon.maklink", "subtask_opt.planners.polygon.pso",
                "subtask_opt.planners.polygon.visibility"),
    "reactive": ("subtask_opt.planners.reactive.simulation",),
    "agv": ("subtask_opt.planners.agv.simulation",),
}
"""Family -> the modules whose import registers its planners."""

__all__ = ["FAMILIES", "SEED_LIMIT", "Outcome", "Planner", "PlannerInfo", "check_seed",
           "get_planner", "planners", "register"]

SEED_LIMIT = 2**63
"""Seeds are integers in [0, SEED_LIMIT)."""


class Planner(Protocol):
    """What every registered planner is."""

    def __call__(self, world: Any, start: Any, goal: Any, *, params: Any = None,
                 seed: int | None = None, stop: Any = None) -> PlanResult: ...


@dataclass(frozen=True)
class PlannerInfo:
    """A registered planner: its family, name, function and one-line description."""

    family: str
    name: str
    plan: Planner
    description: str
    stochastic: bool = False
    iterative: bool = False


_REGISTRY: dict[tuple[str, str], PlannerInfo] = {}


def register(family: str, name: str, *, description: str, stochastic: bool = False,
             iterative: bool = False) -> Callable[[Planner], Planner]:
    """Decorator: register ``plan`` as planner ``name`` of ``family``."""
    if family not in FAMILIES:
        raise ParameterError(f"unknown planner family {family!r}; families: {sorted(FAMILIES)}")

    def deco(fn: Planner) -> Planner:
        _REGISTRY[(family, name)] = PlannerInfo(family, name, fn, description, stochastic,
                                                iterative)
        return fn
    return deco


def planners(family: str) -> dict[str, PlannerInfo]:
    """The planners of ``family`` by name, in registration order (imports the family)."""
    if family not in FAMILIES:
        raise ParameterError(f"unknown planner family {family!r}; families: {sorted(FAMILIES)}")
    for module in FAMILIES[family]:
        importlib.import_module(module)
    return {name: info for (fam, name), info in _REGISTRY.items() if fam == family}


def get_planner(family: str, name: str) -> PlannerInfo:
    """One registered planner; a :class:`ParameterError` names the choices otherwise."""
    found = planners(family)
    if name not in found:
        raise ParameterError(f"unknown {family} planner {name!r}; choose one of "
                             f"{', '.join(found)}")
    return found[name]


def check_seed(seed: object, *, owner: str = "seed") -> int | None:
    """None, or an integer in [0, 2**63) (numpy's generators take no more)."""
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not (
            0 <= seed < SEED_LIMIT):
        raise ParameterError(f"{owner} must be an integer in [0, 2**63), got {seed!r}")
    return int(seed)
