"""Continuous VFF and VFH navigators on the same robot and sonar ring as the fuzzy one.

Both are classic Borenstein-Koren reactive methods, rebuilt for a ring of range
sensors instead of a certainty grid, so that the comparison with
:class:`.fuzzy.FuzzyNavigator` isolates the decision rule:

* :class:`VFFNavigator` (virtual force field): each echo pushes the robot away
  along its beam with a force growing as the echo nears, the goal pulls with a
  constant force; the robot steers toward the resultant.
* :class:`VFHNavigator` (vector field histogram, VFH+ style): a binary polar
  histogram over the beam directions, each echo closer than
  ``threshold_distance`` blocking the directions within the angle its
  body-enlarged width subtends; the robot steers to the free direction nearest
  the goal, turning in place when the goal is behind or nothing is free.

Both share one speed law: full speed when aligned and clear, slowing with the
heading error and to zero when an echo lies in the swept corridor closer than
``radius + safety_margin``, and one guard: the arc of the command is checked
against the walls predicted from the current scan (:func:`.sonar.predict_scan`,
as the fuzzy navigator's admissibility filter does) and the speed is cut until
the arc keeps ``radius + safety_margin`` from them (turning in place when no
speed does). Neither escapes local minima.

Sensor noise: the guard reads every echo ``noise_sigmas`` standard deviations
of the ring's noise closer than measured (:func:`pessimistic_ranges`), so a
reading that came out too long by up to that much cannot talk it into a move
the true wall forbids (with 0.02 m noise VFF once drove into an obstacle it had
just measured 5 cm too far, in ``random-146409670``). The steering and the
speed law use the readings as measured.

The parameter classes are :class:`SonarVFFParams` and :class:`SonarVFHParams`
(the grid family's :mod:`subtask_opt.planners.grid.vff` has its own ``VFFParams``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from subtask_opt.base.errors import require_in_range, require_non_negative, require_positive
from subtask_opt.base.geometry import wrap_angle
from subtask_opt.planners.reactive.fuzzy import NavDecision
from subtask_opt.planners.reactive.sonar import SonarRing, predict_scan
from subtask_opt.planners.reactive.unicycle import Unicycle, integrate_arc

_GUARD_SPEEDS = (1.0, 0.75, 0.5, 0.25)
"""Fractions of the commanded speed the guard tries, fastest first."""

MAX_NOISE_SIGMAS = 10.0
"""Largest ``noise_sigmas`` a navigator accepts."""


def pessimistic_ranges(sonar: SonarRing, ranges: np.ndarray, noise_sigmas: float) -> np.ndarray:
    """``ranges`` with every echo (reading below ``max_range``) moved
    ``noise_sigmas * sonar.noise_std`` closer (not below 0); no-echo readings unchanged."""
    ranges = np.asarray(ranges, dtype=float)
    shift = noise_sigmas * sonar.noise_std
    if shift <= 0.0:
        return ranges
    echo = ranges < sonar.max_range
    return np.where(echo, np.maximum(ranges - shift, 0.0), ranges)


def _guard(robot: Unicycle, sonar: SonarRing, pose: np.ndarray, ranges: np.ndarray,
           v: float, omega: float, safety_margin: float) -> float:
    """The largest of ``v * _GUARD_SPEEDS`` whose arc (end and midpoint) keeps
    ``radius + safety_margin`` from the walls predicted from ``ranges``; 0 if none."""
    if v <= 0.0:
        return 0.0
    speeds = v * np.asarray(_GUARD_SPEEDS)
    cand = integrate_arc(pose, speeds, np.full(speeds.shape, omega), robot.dt)
    mid = integrate_arc(pose, speeds, np.full(speeds.shape, omega), 0.5 * robot.dt)[:, :2]
    _, clearance = predict_scan(sonar, ranges, pose, cand, mid)
    ok = np.flatnonzero(clearance >= robot.radius + safety_margin)
    return float(speeds[ok[0]]) if ok.size else 0.0


def _command(robot: Unicycle, sonar: SonarRing, ranges: np.ndarray, heading_error: float,
             safety_margin: float, slow_distance: float) -> tuple[float, float]:
    """Turn toward ``heading_error`` (reaching it in one step if the limit allows) and
    pick a speed that stops before an echo in the swept corridor."""
    omega = min(max(heading_error / robot.dt, -robot.max_turn_rate), robot.max_turn_rate)
    a = sonar.angles
    ahead = ranges * np.cos(a)
    lateral = np.abs(ranges * np.sin(a))
    in_path = (ranges < sonar.max_range) & (ahead > 0) & (lateral < robot.radius + safety_margin)
    free = float(np.min(ahead[in_path])) if np.any(in_path) else sonar.max_range
    room = (free - robot.radius - safety_margin) / slow_distance
    v = robot.max_speed * max(0.0, math.cos(heading_error)) * min(max(room, 0.0), 1.0)
    return v, omega


@dataclass(frozen=True)
class SonarVFFParams:
    """Virtual force field gains.

    Attributes:
        attraction: constant pull toward the goal (> 0).
        repulsion: gain of the push of an echo at distance r, ``repulsion / r**2`` (>= 0).
        safety_margin: clearance beyond the body radius at which the robot stops.
        slow_distance: distance over which the speed ramps up from 0 (> 0).
        noise_sigmas: the guard reads echoes this many noise standard deviations
            closer than measured (in ``[0, MAX_NOISE_SIGMAS]``; :func:`pessimistic_ranges`).
    """

    attraction: float = 1.0
    repulsion: float = 0.05
    safety_margin: float = 0.08
    slow_distance: float = 0.6
    noise_sigmas: float = 3.0

    def __post_init__(self) -> None:
        require_positive("SonarVFFParams", "attraction", self.attraction)
        require_non_negative("SonarVFFParams", "repulsion", self.repulsion)
        require_non_negative("SonarVFFParams", "safety_margin", self.safety_margin)
        require_positive("SonarVFFParams", "slow_distance", self.slow_distance)
        require_in_range("SonarVFFParams", "noise_sigmas", self.noise_sigmas, 0.0,
                         MAX_NOISE_SIGMAS)


class VFFNavigator:
    """Virtual force field on the sonar ring (no local-minimum escape)."""

    name = "vff"

    def __init__(self, robot: Unicycle, sonar: SonarRing, params: SonarVFFParams | None = None):
        self.robot = robot
        self.sonar = sonar
        self.params = params or SonarVFFParams()

    def reset(self) -> None:
        """Stateless: nothing to forget."""

    def decide(self, pose: np.ndarray, ranges: np.ndarray, goal: np.ndarray) -> NavDecision:
        p = self.params
        heading = float(pose[2])
        g = np.asarray(goal, dtype=float) - pose[:2]
        force = p.attraction * g / max(float(np.hypot(*g)), 1e-12)
        echo = ranges < self.sonar.max_range
        if np.any(echo):
            a = self.sonar.angles[echo] + heading
            r = np.maximum(ranges[echo], 1e-3)
            w = p.repulsion * (1.0 / r - 1.0 / self.sonar.max_range) / r
            force = force - np.array([np.sum(w * np.cos(a)), np.sum(w * np.sin(a))])
        err = float(wrap_angle(math.atan2(force[1], force[0]) - heading))
        v, omega = _command(self.robot, self.sonar, ranges, err, p.safety_margin,
                            p.slow_distance)
        v = _guard(self.robot, self.sonar, pose,
                   pessimistic_ranges(self.sonar, ranges, p.noise_sigmas), v, omega,
                   p.safety_margin)
        return NavDecision(v=v, omega=omega, target=np.asarray(goal, dtype=float))


@dataclass(frozen=True)
class SonarVFHParams:
    """Vector field histogram settings.

    Attributes:
        threshold_distance: echoes closer than this block directions (> 0).
        safety_margin: enlargement of each echo beyond the body radius (>= 0);
            also the stopping clearance of the speed law.
        slow_distance: distance over which the speed ramps up from 0 (> 0).
        noise_sigmas: the guard reads echoes this many noise standard deviations
            closer than measured (in ``[0, MAX_NOISE_SIGMAS]``; :func:`pessimistic_ranges`).
    """

    threshold_distance: float = 1.0
    safety_margin: float = 0.08
    slow_distance: float = 0.6
    noise_sigmas: float = 3.0

    def __post_init__(self) -> None:
        require_positive("SonarVFHParams", "threshold_distance", self.threshold_distance)
        require_non_negative("SonarVFHParams", "safety_margin", self.safety_margin)
        require_positive("SonarVFHParams", "slow_distance", self.slow_distance)
        require_in_range("SonarVFHParams", "noise_sigmas", self.noise_sigmas, 0.0,
                         MAX_NOISE_SIGMAS)


class VFHNavigator:
    """Binary polar histogram on the sonar ring (no local-minimum escape)."""

    name = "vfh"

    def __init__(self, robot: Unicycle, sonar: SonarRing, params: SonarVFHParams | None = None):
        self.robot = robot
        self.sonar = sonar
        self.params = params or SonarVFHParams()

    def reset(self) -> None:
        """Stateless: nothing to forget."""

    def free_directions(self, ranges: np.ndarray) -> np.ndarray:
        """(n_beams,) mask of the beam directions not blocked by a near, enlarged echo."""
        a = self.sonar.angles
        near = ranges < self.params.threshold_distance
        if not np.any(near):
            return np.ones(a.shape[0], dtype=bool)
        r = np.maximum(ranges[near], 1e-6)
        width = np.arcsin(np.minimum(1.0, (self.robot.radius + self.params.safety_margin) / r))
        blocked = np.abs(a[:, None] - a[near][None, :]) <= width[None, :] + 0.5 * self.sonar.spacing
        return ~np.any(blocked, axis=1)

    def decide(self, pose: np.ndarray, ranges: np.ndarray, goal: np.ndarray) -> NavDecision:
        p = self.params
        heading = float(pose[2])
        goal = np.asarray(goal, dtype=float)
        g = float(wrap_angle(math.atan2(goal[1] - pose[1], goal[0] - pose[0]) - heading))
        a = self.sonar.angles
        free = self.free_directions(ranges)
        half_fov = 0.5 * math.radians(self.sonar.fov_deg)
        if abs(g) > half_fov or not np.any(free):
            # goal behind or all blocked: turn in place toward the goal side
            omega = math.copysign(self.robot.max_turn_rate, g if g != 0 else 1.0)
            return NavDecision(v=0.0, omega=omega, target=goal)
        k = int(np.argmin(np.abs(a - g)))
        if free[k]:
            err = g
        else:
            idx = np.flatnonzero(free)
            err = float(a[idx[np.argmin(np.abs(a[idx] - g))]])
        v, omega = _command(self.robot, self.sonar, ranges, err, p.safety_margin,
                            p.slow_distance)
        v = _guard(self.robot, self.sonar, pose,
                   pessimistic_ranges(self.sonar, ranges, p.noise_sigmas), v, omega,
                   p.safety_margin)
        return NavDecision(v=v, omega=omega, target=goal)
