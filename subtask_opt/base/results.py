"""Result types shared by every optimiser and planner.

* :class:`History` - per-generation (or per-iteration) best and mean cost and
  the generations at which the population restarted.
* :class:`PlanResult` - what every mobile-robot planner returns: a path array,
  its length, a success flag and a message, never a silent ``None``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


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


def polyline_length(path: np.ndarray) -> float:
    """Euclidean length of a polyline given as a (k, 2) array."""
    path = np.asarray(path, dtype=float)
    if path.shape[0] < 2:
        return 0.0
    return float(np.sum(np.hypot(*np.diff(path, axis=0).T)))


def count_turns(path: np.ndarray, tol_deg: float = 1e-6) -> int:
    """Number of heading changes along a polyline (collinear points ignored)."""
    path = np.asarray(path, dtype=float)
    if path.shape[0] < 3:
        return 0
    d = np.diff(path, axis=0)
    d = d[np.hypot(d[:, 0], d[:, 1]) > 0]
    if d.shape[0] < 2:
        return 0
    cross = d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0]
    dot = np.sum(d[:-1] * d[1:], axis=1)
    angles = np.degrees(np.abs(np.arctan2(cross, dot)))
    return int(np.count_nonzero(angles > tol_deg))


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
        info: planner-specific extras (JSON-serialisable).
    """

    path: np.ndarray
    success: bool
    message: str
    planner: str
    runtime_s: float = 0.0
    history: History | None = None
    info: dict[str, Any] = field(default_factory=dict)

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
        }
        if self.history is not None:
            out["history"] = self.history.to_dict()
        out.update(self.info)
        return out

    def summary(self) -> str:
        if not self.success:
            return f"{self.planner}: no path ({self.message}), {self.runtime_s * 1e3:.2f} ms"
        return (f"{self.planner}: length {self.length:.4f}, {self.turns} turns, "
                f"{len(self.path)} waypoints, {self.runtime_s * 1e3:.2f} ms")
