"""A ring of range sensors over the robot's front, simulated by ray casting.

Each beam is a straight ray from the robot centre (as in the paper: ``U_k`` is
the distance from the robot centre to the obstacle); a beam that meets nothing
within ``max_range`` reads ``max_range``. Optional Gaussian noise on the echoes
comes from a seeded ``np.random.Generator``.

:func:`predict_scan` implements SPEC §3's prediction of the scan at a
via-point candidate from the current scan alone (rigid transform; straight
beams; each echo a wall perpendicular to its beam; unseen space open).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    require_in_range,
    require_int,
    require_positive,
)
from subtask_opt.planners.reactive import _kernels as K

if TYPE_CHECKING:
    from subtask_opt.planners.polygon.world import PolygonWorld


MAX_BEAMS = 3600
"""Most sensors a ring may have (one every 0.1 degree over a full circle)."""
MAX_RANGE = 1e6
"""Longest sensing range (world units; keeps sums of readings far from overflow)."""


@dataclass(frozen=True)
class SonarRing:
    """A fan of ``n_beams`` range sensors spread evenly over the robot's front.

    Beam ``k`` points at the centre of the k-th of ``n_beams`` equal sectors of
    the field of view, measured from the heading: with the defaults (18 beams,
    180 degrees) the beams sit at -85, -75, ..., +85 degrees.

    Attributes:
        n_beams: number of sensors (1 to :data:`MAX_BEAMS`; 18 on the paper's LCAR robot).
        fov_deg: total field of view in degrees, in (0, 360].
        max_range: sensing range ``R_max`` (world units, in ``(0, MAX_RANGE]``).
        noise_std: standard deviation of the Gaussian noise added to echoes
            (readings below ``max_range``), in ``[0, max_range]``; noisy readings
            are clipped to ``[0, max_range]``.
        overlap: width of each predicted wall relative to its beam's sector
            (>= 1 closes the gaps between neighbouring echoes on slanted walls).
    """

    n_beams: int = 18
    fov_deg: float = 180.0
    max_range: float = 2.5
    noise_std: float = 0.0
    overlap: float = 1.5

    def __post_init__(self) -> None:
        require_int("SonarRing", "n_beams", self.n_beams, 1, MAX_BEAMS)
        require_in_range("SonarRing", "fov_deg", self.fov_deg, 1e-9, 360.0)
        require_positive("SonarRing", "max_range", self.max_range)
        require_in_range("SonarRing", "max_range", self.max_range, 0.0, MAX_RANGE)
        require_in_range("SonarRing", "noise_std", self.noise_std, 0.0, self.max_range)
        require_in_range("SonarRing", "overlap", self.overlap, 1.0, 10.0)

    @property
    def spacing(self) -> float:
        """Angular width of one beam's sector (rad)."""
        return math.radians(self.fov_deg) / self.n_beams

    @cached_property
    def angles(self) -> np.ndarray:
        """Beam directions in the robot frame (rad, increasing, centred on 0; read-only)."""
        a = (np.arange(self.n_beams) + 0.5) * self.spacing - 0.5 * math.radians(self.fov_deg)
        a.flags.writeable = False
        return a

    def world_angles(self, pose: np.ndarray) -> np.ndarray:
        """Beam directions in the world frame for a robot at ``pose``."""
        return self.angles + float(pose[2])

    def scan(self, edges: np.ndarray, pose: np.ndarray,
             rng: np.random.Generator | None = None) -> np.ndarray:
        """Readings at ``pose`` against ``edges`` ((m, 4) rows x1, y1, x2, y2).

        ``rng`` is needed only when ``noise_std > 0``.
        """
        pose = np.asarray(pose, dtype=float)
        ranges = K.cast_rays(edges, float(pose[0]), float(pose[1]), self.world_angles(pose),
                             float(self.max_range))
        if self.noise_std > 0.0:
            if rng is None:
                raise ParameterError("SonarRing.scan needs an rng when noise_std > 0")
            noise = rng.normal(0.0, self.noise_std, size=ranges.shape[0])
            echo = ranges < self.max_range
            ranges = np.where(echo, np.clip(ranges + noise, 0.0, self.max_range), ranges)
        return ranges

    def hit_points(self, pose: np.ndarray, ranges: np.ndarray) -> np.ndarray:
        """World coordinates of the beam ends ((n, 2)) for plotting."""
        a = self.world_angles(pose)
        return np.column_stack([pose[0] + ranges * np.cos(a), pose[1] + ranges * np.sin(a)])


def scene_edges(world: PolygonWorld) -> np.ndarray:
    """All walls the sensors and the body can meet: obstacle edges and the world boundary."""
    edges = np.asarray(world.edges, dtype=float).reshape(-1, 4)
    boundary = np.asarray(world.boundary_edges, dtype=float).reshape(-1, 4)
    return np.ascontiguousarray(np.vstack([edges, boundary]))


def to_robot_frame(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Express world points ``(..., 2)`` (or poses ``(..., 3)``) in the frame of ``pose``."""
    pose = np.asarray(pose, dtype=float)
    points = np.asarray(points, dtype=float)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx = points[..., 0] - pose[0]
    dy = points[..., 1] - pose[1]
    out = np.empty(points.shape)
    out[..., 0] = c * dx + s * dy
    out[..., 1] = -s * dx + c * dy
    if points.shape[-1] == 3:
        out[..., 2] = points[..., 2] - pose[2]
    return out


def predict_scan(ring: SonarRing, ranges: np.ndarray, pose: np.ndarray,
                 candidates: np.ndarray,
                 midpoints: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Predict the readings at candidate poses from the scan taken at ``pose``.

    Args:
        ring: the sensor ring that produced ``ranges``.
        ranges: (n_beams,) readings taken at ``pose``.
        pose: current pose (x, y, heading), world frame.
        candidates: (c, 3) candidate poses, world frame.
        midpoints: optional (c, 2) points on the way to each candidate (world
            frame) also counted in the clearance; defaults to the candidates.

    Returns:
        ``(pred, clearance)``: (c, n_beams) predicted readings and (c,) the
        smallest distance from each candidate (or its midpoint) to a predicted
        wall (``inf`` when the scan has no echo).
    """
    ranges = np.asarray(ranges, dtype=float)
    candidates = np.atleast_2d(np.asarray(candidates, dtype=float))
    if ranges.shape != (ring.n_beams,):
        raise InputDataError(f"ranges must have shape ({ring.n_beams},), got {ranges.shape}")
    if candidates.shape[1] != 3:
        raise InputDataError(f"candidates must have shape (c, 3), got {candidates.shape}")
    cand = to_robot_frame(pose, candidates)
    mid = cand[:, :2] if midpoints is None else to_robot_frame(pose, midpoints)[:, :2]
    params = K.RingParams(float(ring.spacing), float(ring.max_range), float(ring.overlap))
    return K.predict_scans(ranges, ring.angles, params, np.ascontiguousarray(cand),
                           np.ascontiguousarray(mid))
