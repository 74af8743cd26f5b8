"""Differential-drive (unicycle) robot: kinematics, limits, sampling time, body radius.

A pose is ``(x, y, heading)`` with the heading in radians. Within one sampling
period the robot holds a forward speed ``v`` and a turn rate ``omega``, so it
moves along a circular arc (a straight segment when ``omega == 0``); the arc is
integrated exactly, so a via-point candidate is exactly where the robot ends up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from subtask_opt.base.errors import ParameterError, require_int, require_positive
from subtask_opt.planners.reactive import _kernels as K

MAX_GRID = 1000
"""Largest number of headings or speeds in the via-point command grid."""


@dataclass(frozen=True)
class Unicycle:
    """A differential-drive robot with a circular body.

    Attributes:
        max_speed: largest forward speed (world units per second, > 0); the
            robot never drives backwards.
        max_turn_rate: largest turn rate magnitude (rad/s, > 0); one period
            turns at most half a turn (``max_turn_rate * dt <= pi``).
        dt: sampling time (s, > 0): one decision per period.
        radius: radius of the body circle (world units, > 0).
    """

    max_speed: float = 0.3
    max_turn_rate: float = 1.2
    dt: float = 0.5
    radius: float = 0.2

    def __post_init__(self) -> None:
        for name in ("max_speed", "max_turn_rate", "dt", "radius"):
            require_positive("Unicycle", name, getattr(self, name))
        if self.max_turn_rate * self.dt > math.pi:
            raise ParameterError(
                f"Unicycle.max_turn_rate must be <= pi / dt = {math.pi / self.dt:g} rad/s "
                f"(at most half a turn per sampling period of {self.dt:g} s), "
                f"got {self.max_turn_rate!r}")

    @property
    def max_step(self) -> float:
        """Longest distance travelled in one sampling period."""
        return self.max_speed * self.dt

    def clip(self, v: float, omega: float) -> tuple[float, float]:
        """Clamp a command to the limits (speed in ``[0, max_speed]``)."""
        return (min(max(float(v), 0.0), self.max_speed),
                min(max(float(omega), -self.max_turn_rate), self.max_turn_rate))

    def step(self, pose: np.ndarray, v: float, omega: float) -> np.ndarray:
        """Pose after one sampling period with the (clamped) command ``(v, omega)``."""
        v, omega = self.clip(v, omega)
        return integrate_arc(np.asarray(pose, dtype=float), v, omega, self.dt)

    def commands(self, n_headings: int, n_speeds: int) -> tuple[np.ndarray, np.ndarray]:
        """The via-point command grid: headings x speeds, flattened.

        Heading changes are spread evenly over ``[-max_turn_rate dt, +max_turn_rate dt]``
        (``n_headings`` odd keeps "straight ahead" in the set); speeds over
        ``[0, max_speed]`` (speed 0 = turn in place, always collision-free).

        Returns:
            ``(v, omega)`` arrays of length ``n_headings * n_speeds``, heading-major.
        """
        require_int("Unicycle.commands", "n_headings", n_headings, 1, MAX_GRID)
        require_int("Unicycle.commands", "n_speeds", n_speeds, 1, MAX_GRID)
        omegas = np.linspace(-self.max_turn_rate, self.max_turn_rate, n_headings) \
            if n_headings > 1 else np.zeros(1)
        speeds = np.linspace(0.0, self.max_speed, n_speeds) if n_speeds > 1 \
            else np.array([self.max_speed])
        om, sp = np.meshgrid(omegas, speeds, indexing="ij")
        return sp.ravel().copy(), om.ravel().copy()


def integrate_arc(pose: np.ndarray, v: float | np.ndarray, omega: float | np.ndarray,
                  dt: float) -> np.ndarray:
    """Exact unicycle motion over ``dt``; broadcasts over arrays of commands.

    Returns an array of shape ``(..., 3)``: x, y and the heading wrapped to [-pi, pi).
    """
    x, y, th = float(pose[0]), float(pose[1]), float(pose[2])
    if np.ndim(v) == 0 and np.ndim(omega) == 0:
        return np.array(K.arc(x, y, th, float(v), float(omega), float(dt)))
    vb, ob = np.broadcast_arrays(np.asarray(v, dtype=float), np.asarray(omega, dtype=float))
    out = K.arc_poses(x, y, th, np.ascontiguousarray(vb).ravel(),
                    np.ascontiguousarray(ob).ravel(), float(dt))
    return out.reshape(vb.shape + (3,))
