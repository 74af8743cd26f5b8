"""Targets: the places a tour visits, one type for every robot.

A :class:`Targets` is either

* **planar** (a planar arm): ``points`` (N, 2) in metres in the robot model's world
  frame, optional tool angles ``theta`` (N,); read by :func:`~subtask_opt.arm.tasks.
  load_subtasks` (``x,y[,theta]`` files) and built in by
  :func:`~subtask_opt.arm.tasks.builtin_case`; or
* **3-D** (a serial arm): ``points`` (N, 3) with each target's candidate tool
  ``poses`` (a tool axis ``x,y,z,dx,dy,dz`` sampled about the axis, or one full pose
  ``x,y,z,qx,qy,qz,qw``), built by :func:`~subtask_opt.arm.poses.make_targets` and read
  by :func:`~subtask_opt.arm.poses.load_targets`.

:func:`subtask_opt.load_targets` reads either kind from a file; a problem refuses the
kind its robot cannot reach (a planar arm's targets are planar, a serial arm's 3-D).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError, require_in_range

DUPLICATE_TOL = 1e-9
"""Two planar targets closer than this (m, Euclidean) are duplicates and refused."""
MAX_COORDINATE = 1e6
"""Planar coordinates are in [-1e6, 1e6] m."""
MAX_SUBTASKS = 20_000
"""The most planar targets a set may hold (the N x N matrices of a time model: 3.2 GB at
20 000)."""
MIN_AXIS_STEP = 5.0
"""The finest ``axis_step`` (degrees): at most 72 poses per tool-axis target."""


@dataclass(frozen=True, eq=False)
class Targets:
    """N targets of a tour (module doc): planar points, or 3-D points with their poses.

    Attributes:
        points: (N, 2) planar positions (m; N >= 3, finite, no two equal), or (N, 3) 3-D
            target points as given (before the standoff).
        theta: (planar) optional (N,) tool angles (rad). The 2-DOF arm cannot choose its
            tool angle (it follows from the position and elbow branch); when given, the
            Cartesian time models use these angles for the rotation instead of the arm's.
        name: a label (file stem or case name).
        poses: (3-D) one read-only (k_i, 4, 4) array per target, the candidate tool poses
            (homogeneous, base frame, metres); k_i = 1 for a full pose, the number of
            sampled rotations for a tool axis. None for planar targets.
        axes: (3-D) (N, 3) unit tool z axes (for full poses, the pose's z axis).
        free_axis: (3-D) (N,) True where the rotation about the axis is free (sampled).
        axis_step: (3-D) sampling step of the free rotation (degrees).
        standoff: (3-D) distance the tool backs off along its z axis (m).
    """

    points: np.ndarray
    theta: np.ndarray | None = None
    name: str = ""
    poses: tuple[np.ndarray, ...] | None = None
    axes: np.ndarray | None = None
    free_axis: np.ndarray | None = None
    axis_step: float = 45.0
    standoff: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):
            raise ParameterError(f"Targets.name must be a string, got {self.name!r}")
        if self.poses is None:
            self._check_planar()
        else:
            self._check_3d()

    def _check_planar(self) -> None:
        for field in ("axes", "free_axis"):
            if getattr(self, field) is not None:
                raise ParameterError(f"Targets.{field} applies to 3-D targets (with poses); "
                                     "these are planar")
        if self.axis_step != 45.0 or self.standoff != 0.0:
            raise ParameterError("Targets.axis_step and standoff apply to 3-D targets "
                                 "(with poses); these are planar")
        pts = _real_array(self.points, "Targets.points", "numbers of shape (N, 2)")
        if pts.ndim != 2 or pts.shape[1] != 2:
            hint = " (3-D targets need their poses: make_targets)" if (
                pts.ndim == 2 and pts.shape[1] == 3) else ""
            raise InputDataError(f"Targets.points must have shape (N, 2), got "
                                 f"{pts.shape}{hint}")
        if pts.shape[0] < 3:
            raise InputDataError(f"Targets.points needs at least 3 subtasks, got {pts.shape[0]}")
        if pts.shape[0] > MAX_SUBTASKS:
            raise InputDataError(f"Targets.points has {pts.shape[0]} subtasks; the limit is "
                                 f"{MAX_SUBTASKS}")
        bad = np.flatnonzero(~(np.abs(pts) <= MAX_COORDINATE).all(axis=1))
        if bad.size:
            raise InputDataError(f"subtask {bad[0]} is {pts[bad[0]].tolist()}: coordinates "
                                 f"must be finite and within +-{MAX_COORDINATE:g} m")
        pair = _close_pair(pts, DUPLICATE_TOL)
        if pair is not None:
            i, j = pair
            raise InputDataError(
                f"subtasks {i} and {j} are duplicates: {pts[i].tolist()} and "
                f"{pts[j].tolist()} are closer than {DUPLICATE_TOL:g} m")
        pts.setflags(write=False)
        object.__setattr__(self, "points", pts)
        if self.theta is not None:
            th = _real_array(self.theta, "Targets.theta", f"{pts.shape[0]} numbers")
            if th.shape != (pts.shape[0],):
                raise InputDataError(
                    f"Targets.theta must have {pts.shape[0]} values (one per subtask), "
                    f"got shape {th.shape}")
            bad = np.flatnonzero(~np.isfinite(th))
            if bad.size:
                raise InputDataError(f"theta of subtask {bad[0]} is not finite: {th[bad[0]]}")
            th.setflags(write=False)
            object.__setattr__(self, "theta", th)

    def _check_3d(self) -> None:
        if self.theta is not None:
            raise ParameterError("Targets.theta applies to planar targets; 3-D targets give "
                                 "their tool orientation in their poses")
        n = len(self.poses or ())
        for field, shape in (("points", (n, 3)), ("axes", (n, 3)), ("free_axis", (n,))):
            if getattr(self, field) is None:
                raise ParameterError(f"3-D Targets need {field} of shape {shape}")
            arr = np.asarray(getattr(self, field))
            if arr.shape != shape:
                raise ParameterError(f"Targets.{field} must have shape {shape}, "
                                     f"got {arr.shape}")
            arr = arr.copy()
            arr.setflags(write=False)
            object.__setattr__(self, field, arr)
        poses = []
        for i, p in enumerate(self.poses or ()):
            arr = np.array(p, dtype=np.float64)
            if arr.ndim != 3 or arr.shape[1:] != (4, 4) or arr.shape[0] == 0:
                raise ParameterError(f"Targets.poses[{i}] must have shape (k, 4, 4), "
                                     f"got {arr.shape}")
            arr.setflags(write=False)
            poses.append(arr)
        object.__setattr__(self, "poses", tuple(poses))
        require_in_range("Targets", "axis_step", self.axis_step, MIN_AXIS_STEP, 360.0)
        require_in_range("Targets", "standoff", self.standoff, -1e3, 1e3)

    @property
    def planar(self) -> bool:
        """Whether these are planar points (a planar arm's targets) rather than 3-D ones."""
        return self.poses is None

    def __len__(self) -> int:
        return int(self.points.shape[0])

    @property
    def n_candidates(self) -> int:
        """Candidate tool poses over all targets (planar: one per point)."""
        return len(self) if self.poses is None else sum(p.shape[0] for p in self.poses)

    def __repr__(self) -> str:
        if self.poses is None:
            theta = "" if self.theta is None else ", with theta"
            return f"Targets({self.name!r}, {len(self)} planar subtasks{theta})"
        return (f"Targets({self.name!r}, {len(self)} 3-D targets, {self.n_candidates} "
                "candidate poses)")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form of planar targets (the format
        :func:`~subtask_opt.arm.tasks.load_subtasks` reads)."""
        if self.poses is not None:
            raise ParameterError("Targets.to_dict writes planar targets; 3-D targets are "
                                 "written as their x,y,z,dx,dy,dz or pose rows")
        out: dict[str, Any] = {"name": self.name, "points": self.points.tolist()}
        if self.theta is not None:
            out["theta"] = self.theta.tolist()
        return out


def describe(value: Any) -> str:
    """What ``value`` is, for an error message: planar or 3-D Targets, or its type."""
    if isinstance(value, Targets):
        return f"{'planar' if value.planar else '3-D'} Targets"
    return type(value).__name__


def _real_array(values: Any, what: str, expected: str) -> np.ndarray:
    """``values`` as float64, refusing strings, complex numbers and overflowing integers."""
    try:
        arr = np.asarray(values)
        if arr.dtype.kind not in "iuf":
            raise TypeError
        return np.array(arr, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        shown = repr(values)
        raise InputDataError(f"{what} must be real {expected}, got "
                             f"{shown[:80] + '...' if len(shown) > 80 else shown}") from None


def _close_pair(pts: np.ndarray, tol: float) -> tuple[int, int] | None:
    """Two indices of points closer than ``tol`` (Euclidean), or None; O(N log N) typical."""
    order = np.argsort(pts[:, 0], kind="stable")
    xs = pts[order, 0]
    for a in range(len(order)):
        b = a + 1
        while b < len(order) and xs[b] - xs[a] < tol:
            i, j = int(order[a]), int(order[b])
            if math.hypot(*(pts[i] - pts[j])) < tol:
                return (min(i, j), max(i, j))
            b += 1
    return None


__all__ = ["DUPLICATE_TOL", "MAX_COORDINATE", "MAX_SUBTASKS", "MIN_AXIS_STEP", "Targets",
           "describe"]
