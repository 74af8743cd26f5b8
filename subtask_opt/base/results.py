"""Result types shared by every optimiser and planner.

* :class:`History` - per-generation (or per-iteration) best and mean cost and
  the generations at which the population restarted.
* :class:`PlanResult` - what every mobile-robot planner returns: a path array,
  its length, a success flag and a message, never a silent ``None``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np

from subtask_opt.base.geometry import count_turns, polyline_length


@dataclass(frozen=True)
class History:
    """Cost per generation of an iterative optimiser.

    Attributes:
        initial_best: best cost of the initial population (generation 0).
        best_cost: best cost found so far, after each generation (length G).
        mean_cost: mean cost of the population in each generation (length G).
        restarts: generation numbers (1-based, as in ``best_cost``) at which
            the population was re-seeded.
    """

    initial_best: float
    best_cost: np.ndarray
    mean_cost: np.ndarray
    restarts: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    @property
    def generations(self) -> int:
        return int(self.best_cost.shape[0])

    def generation_of_best(self, rtol: float = 1e-9) -> int:
        """Generation at which the final best was first reached (0: the initial population)."""
        if self.generations == 0:
            return 0
        final = self.best_cost[-1]
        if self.initial_best <= final + rtol * abs(final):
            return 0
        hit = np.flatnonzero(self.best_cost <= final + rtol * abs(final))
        return int(hit[0]) + 1

    def to_dict(self) -> dict[str, Any]:
        return {
            "initial_best": self.initial_best,
            "best_cost": self.best_cost.tolist(),
            "mean_cost": self.mean_cost.tolist(),
            "restarts": self.restarts.tolist(),
        }


class Outcome(StrEnum):
    """How a plan ended; shared by every planner family (JSON: the value)."""

    SUCCESS = "success"
    NO_PATH = "no_path"
    STALL = "stall"
    TIMEOUT = "timeout"
    COLLISION = "collision"


OUTCOMES = tuple(o.value for o in Outcome)


def _check_json_safe(value: Any, where: str, depth: int = 0) -> None:
    """Raise ValueError unless ``value`` is plain JSON data (no numpy arrays)."""
    if depth > 32:
        raise ValueError(f"{where} is nested deeper than 32 levels")
    if value is None or isinstance(value, (str, bool, int, float)):
        return
    if isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_json_safe(v, f"{where}[{i}]", depth + 1)
        return
    if isinstance(value, dict):
        for k, v in value.items():
            if not isinstance(k, str):
                raise ValueError(f"{where} has a non-string key {k!r}")
            _check_json_safe(v, f"{where}[{k!r}]", depth + 1)
        return
    raise ValueError(f"{where} must be JSON data, got {type(value).__name__}")


@dataclass(frozen=True)
class PlanResult:
    """The answer of a path planner.

    Attributes:
        path: (k, 2) float array of waypoints from start to goal, in the
            planner's world coordinates (grid planners: cell x, y). Empty
            (shape (0, 2)) when no path was found.
        success: whether the path reaches the goal.
        message: why it failed (or ``"ok"``).
        planner: name of the planner that produced it.
        runtime_s: wall time of the planning call (after JIT warm-up if the
            caller warmed up).
        history: per-iteration costs for iterative planners (GA, PSO).
        info: planner-specific extras; JSON-safe (str, bool, int, float, None,
            lists and dicts of them), checked here.
        outcome: how the plan ended (``"success"``, ``"no_path"``, ``"stall"``,
            ``"timeout"``, ``"collision"``); default: from ``success``.
    """

    path: np.ndarray
    success: bool
    message: str
    planner: str
    runtime_s: float = 0.0
    history: History | None = None
    info: dict[str, Any] = field(default_factory=dict)
    outcome: Outcome | str = ""

    def __post_init__(self) -> None:
        path = np.asarray(self.path, dtype=float).reshape(-1, 2)
        object.__setattr__(self, "path", path)
        if not self.outcome:
            default = Outcome.SUCCESS if self.success else Outcome.NO_PATH
            object.__setattr__(self, "outcome", default)
        if self.outcome not in OUTCOMES:
            raise ValueError(f"PlanResult.outcome must be one of {OUTCOMES}, got {self.outcome!r}")
        object.__setattr__(self, "outcome", Outcome(self.outcome))
        if self.success != (self.outcome == "success"):
            raise ValueError(f"PlanResult: success={self.success} contradicts "
                             f"outcome={self.outcome!r}")
        _check_json_safe(self.info, "PlanResult.info")

    @property
    def length(self) -> float:
        return polyline_length(self.path) if self.success else float("inf")

    @property
    def turns(self) -> int:
        return count_turns(self.path)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "planner": self.planner,
            "success": bool(self.success),
            "message": self.message,
            "length": self.length if self.success else None,
            "turns": self.turns,
            "path": np.asarray(self.path, dtype=float).tolist(),
            "runtime_s": self.runtime_s,
            "outcome": Outcome(self.outcome).value,
        }
        if self.history is not None:
            out["history"] = self.history.to_dict()
        out["info"] = dict(self.info)
        return out

    def summary(self) -> str:
        if not self.success:
            return f"{self.planner}: no path ({self.message}), {self.runtime_s * 1e3:.2f} ms"
        return (f"{self.planner}: length {self.length:.4f}, {self.turns} turns, "
                f"{len(self.path)} waypoints, {self.runtime_s * 1e3:.2f} ms")
