"""What a tour means for the arm: leg times, moves, configurations, legs it cannot drive.

:func:`subtask_opt.solve` answers with search facts (:class:`~subtask_opt.tour.solve.Result`);
for an arm problem the result also carries a :class:`TourReport` built here, which
describes only the tour that was returned: a Cartesian model's straight lines are
checked for the tour's N legs only. All-pairs diagnostics of the time model (every
straight line of the Cartesian models when the problem asks for them with
``check_all_legs``, every line of the ``line`` model) sit apart, under
:attr:`TourReport.diagnostics`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from subtask_opt.arm.planar_problem import PlanarProblem

BRANCH_LETTERS = "du"  # elbow down, elbow up


@dataclass(frozen=True)
class TourLeg:
    """One leg of the tour: from -> to, how it is driven and what is wrong with it."""

    index: int
    start: int
    end: int
    configurations: tuple[int, int]
    distance: float
    time: float
    move: str
    notes: tuple[str, ...] = ()
    infeasible_line: bool = False
    """A straight line the arm cannot drive (Cartesian models: outside the
    annulus, a joint limit or an elbow change; ``line``: replaced or excluded)."""
    overspeed: float = 0.0
    """Cartesian models: the joint speed ratio of the straight line, when > 1."""


class ArmReport:
    """What a tour means for the arm, the same for every robot (``Result.report``).

    Every report has ``robot``, ``time_model``, ``configurations_mode``, ``legs`` (one
    :class:`TourLeg` per leg driven, in order; a home is stop -1) and ``problem`` (the
    compiled problem, for :func:`subtask_opt.trajectory`), and gives the summary's lines
    (:meth:`header`, :meth:`order_lines`), a per-leg table, a warning line or None, and
    its JSON (:meth:`to_dict`, whose first keys are the same for every robot:
    :meth:`common_dict`). :class:`TourReport` is a planar arm's, ``SerialReport``
    (:mod:`subtask_opt.arm.serial_problem`) a serial arm's.
    """

    robot: str
    time_model: str
    configurations_mode: str
    problem: Any
    legs: tuple[TourLeg, ...]

    @property
    def infeasible(self) -> tuple[TourLeg, ...]:
        """Legs the arm cannot drive as the model promised."""
        return tuple(leg for leg in self.legs if leg.infeasible_line or leg.overspeed > 1.0)

    def common_dict(self) -> dict[str, Any]:
        """The JSON keys every robot's report has: who, which model, and every leg."""
        return {
            "robot": self.robot,
            "time_model": self.time_model,
            "configurations_mode": self.configurations_mode,
            "legs": [{"leg": leg.index, "from": leg.start, "to": leg.end,
                      "configurations": list(leg.configurations), "distance": leg.distance,
                      "time": leg.time, "move": leg.move, "notes": list(leg.notes)}
                     for leg in self.legs],
            "infeasible_legs": [
                {"leg": leg.index, "from": leg.start, "to": leg.end,
                 "reason": "; ".join(leg.notes) or "straight line over a joint limit",
                 **({"speed_ratio": leg.overspeed} if leg.overspeed > 1.0 else {})}
                for leg in self.infeasible],
        }


@dataclass(frozen=True)
class TourReport(ArmReport):
    """A planar arm's view of a tour (only the tour's legs; all-pairs figures in
    ``diagnostics``)."""

    robot: str
    time_model: str
    configurations_mode: str
    configurations: np.ndarray
    legs: tuple[TourLeg, ...]
    diagnostics: dict[str, Any] = field(default_factory=dict)
    problem: Any = field(default=None, repr=False, compare=False)
    """The problem the tour belongs to (for :func:`subtask_opt.trajectory`)."""

    @property
    def leg_moves(self) -> tuple[str, ...]:
        return tuple(leg.move for leg in self.legs)

    @property
    def configuration_changes(self) -> int:
        """Legs whose two ends use different elbow configurations."""
        return sum(leg.configurations[0] != leg.configurations[1] for leg in self.legs)

    def leg_counts(self) -> dict[str, Any] | None:
        """(Cartesian models) how many of the tour's straight legs the arm cannot drive:
        ``n_legs``, ``n_impossible``, ``n_overspeed`` (feasible but over a joint speed
        limit) and ``worst_ratio`` (largest joint speed ratio of those); else None."""
        if self.time_model not in ("paper", "trapezoid"):
            return None
        return {"n_legs": len(self.legs),
                "n_impossible": sum(leg.infeasible_line for leg in self.legs),
                "n_overspeed": sum(leg.overspeed > 1.0 for leg in self.legs),
                "worst_ratio": max((leg.overspeed for leg in self.legs), default=0.0)}

    def header(self, n: int) -> str:
        """The summary's first line for an answer of ``n`` subtasks."""
        return f"{n} subtasks, {self.time_model} time model, robot {self.robot}"

    def order_lines(self, order: np.ndarray) -> list[str]:
        """The summary's lines after the order: the chosen elbows, when they were chosen."""
        if self.configurations_mode != "optimize":
            return []
        c = self.configurations[order]
        return ["elbow: " + " ".join("du"[int(b)] for b in c)
                + f"  (d down, u up; {self.configuration_changes} changes)"]

    def warning(self) -> str | None:
        """One line when a Cartesian model's tour breaks the arm's joint limits."""
        counts = self.leg_counts()
        if counts is None or not self.infeasible:
            return None
        impossible, fast = counts["n_impossible"], counts["n_overspeed"]
        return (f"{impossible + fast} of the tour's {len(self.legs)} straight-line legs break "
                f"a joint limit ({impossible} impossible as a straight line, {fast} over a "
                f"joint speed limit, worst x{counts['worst_ratio']:.2f}); use --time-model "
                "joint or line for times the arm can achieve")

    def leg_table(self) -> str:
        """One row per leg: from, to, elbow branches, distance, time, move, notes."""
        rows = [f"{'leg':>4} {'from':>5} {'to':>5} {'elbow':>6} {'dist [m]':>9} "
                f"{'time [s]':>9} {'move':>5}  notes"]
        for leg in self.legs:
            ca, cb = leg.configurations
            elbow = BRANCH_LETTERS[ca] + ("->" + BRANCH_LETTERS[cb] if ca != cb else "")
            start, end = ("home" if v < 0 else str(v) for v in (leg.start, leg.end))
            rows.append(f"{leg.index:>4} {start:>5} {end:>5} {elbow:>6} "
                        f"{leg.distance:>9.4f} {leg.time:>9.4f} {leg.move:>5}  "
                        f"{', '.join(leg.notes)}")
        return "\n".join(rows)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the tour's legs, configurations and infeasible legs; diagnostics apart."""
        return {
            **self.common_dict(),
            "configurations": [int(c) for c in self.configurations],
            "leg_moves": list(self.leg_moves),
            "tour_leg_check": self.leg_counts(),
            "diagnostics": self.diagnostics,
        }


def tour_report(problem: PlanarProblem, order: np.ndarray, configurations: np.ndarray,
                leg_times: np.ndarray, home: int | None = None) -> TourReport:
    """The report of the tour ``order`` at ``configurations`` (by subtask index): its
    ``len(leg_times)`` legs, ``order[k] -> order[k + 1]`` (a closed tour's last one back
    to ``order[0]``; an open path has one leg fewer). ``home``: the subtask that is the
    home point, stop -1 in the legs."""
    timing = problem.timing
    check = timing.leg_check
    points = problem.subtasks.points
    moves = timing.moves(configurations)
    starts = np.asarray(order)[:len(leg_times)]
    ends = np.roll(order, -1)[:len(leg_times)]
    if check is not None:  # the tour's legs only; all pairs when the problem asks
        outside, ratio = check.legs(starts, ends)
    legs = []
    for i in range(len(leg_times)):
        a, b = int(starts[i]), int(ends[i])
        ca, cb = int(configurations[a]), int(configurations[b])
        notes: list[str] = []
        infeasible = False
        overspeed = 0.0
        if ca != cb:
            notes.append("elbow change")
        if check is not None:
            if outside[i]:
                infeasible = True
                notes.append("straight line impossible (inner disc, joint limit or elbow change)")
            elif ratio[i] > 1.0:
                overspeed = float(ratio[i])
                notes.append(f"joint speed x{overspeed:.2f} over limit")
        if problem.time_model == "line" and ca == cb:
            why = timing.line_failure(a, b, ca, cb)
            if why is not None:
                infeasible = True
                notes.append(f"line infeasible ({why})")
        move = {0: "joint", 1: "line"}[int(moves[a, b])] if moves is not None else "line"
        legs.append(TourLeg(i, -1 if a == home else a, -1 if b == home else b, (ca, cb),
                            float(np.hypot(*(points[a] - points[b]))), float(leg_times[i]),
                            move, tuple(notes), infeasible, overspeed))
    diagnostics: dict[str, Any] = {}
    if check is not None and problem.check_all_legs:
        diagnostics["all_pairs_leg_check"] = check.to_dict()
    summary = timing.line_summary(order, configurations) if problem.time_model == "line" else None
    if summary is not None:
        diagnostics["all_pairs_lines"] = {k: v for k, v in summary.items()
                                          if k != "tour_legs_not_straight"}
    return TourReport(robot=problem.arm.name, time_model=problem.time_model,
                      configurations_mode=str(problem.configurations),
                      configurations=np.asarray(configurations, dtype=np.int64),
                      legs=tuple(legs), diagnostics=diagnostics, problem=problem)
