"""The planar two-link arm: a Pinocchio model plus the limits URDF cannot hold.

An :class:`Arm` is built once from a URDF (the Pinocchio ``model``) and keeps a
Pinocchio ``data`` as scratch space. Its link lengths, base position, joint
axis signs and angle offsets are read from the model itself (forward
kinematics at q = 0), so any URDF with two revolute joints about axes parallel
to the world z axis works. Coordinates are metres in the robot model's world
frame; the arm moves in a plane z = const and a subtask is a point (x, y).

Elbow branches (see also :mod:`subtask_opt.kinematics._kernels`): branch 0,
"elbow down", puts the elbow on the clockwise (right-hand) side of the line
from the base to the tip; branch 1, "elbow up", on the counter-clockwise side.
For an arm reaching along +x with counter-clockwise joints this is the usual
picture: elbow below the line (down) or above it (up).

Robots shipped: ``planar_2r`` (ours, ``robots/planar_2r.urdf`` + ``.json``) and
``asr_twodof`` (example-robot-data's ``TwoDofs.urdf``, located through the
installed distribution, with ``robots/asr_twodof.json`` for its limits).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    UnreachableError,
    require_in_range,
)
from subtask_opt.base.files import check_input_file, parse_json, quiet_stderr, read_text
from subtask_opt.kinematics import _kernels as _k
from subtask_opt.kinematics.limit_arrays import LIMIT_RANGE, freeze_limit_arrays
from subtask_opt.kinematics.serial import example_robot_data_share, robots_dir

ROBOT_NAMES: tuple[str, ...] = ("planar_2r", "asr_twodof")
BRANCH_NAMES: tuple[str, str] = ("elbow-down", "elbow-up")

# Tolerance for "this axis is the world z axis" when reading a URDF.
_AXIS_TOL = 1e-6


@dataclass(frozen=True)
class CartesianLimits:
    """Limits of the tool in the plane (eq. 16 of the paper).

    Attributes:
        kv: translation speed limit Kv (m/s).
        ka: translation acceleration limit Ka (m/s^2).
        kw: rotation speed limit Kw (rad/s).
        kw_dot: rotation acceleration limit Kw_dot (rad/s^2).
    """

    kv: float
    ka: float
    kw: float
    kw_dot: float

    def __post_init__(self) -> None:
        for name in ("kv", "ka", "kw", "kw_dot"):
            value = getattr(self, name)
            require_in_range("CartesianLimits", name, value, *LIMIT_RANGE)
            object.__setattr__(self, name, float(value))


@dataclass(frozen=True, eq=False)
class JointLimits:
    """Per-joint limits, arrays of shape (2,) ordered as the model's joints.

    Attributes:
        lower, upper: position limits (rad), lower < upper.
        velocity: speed limits (rad/s) > 0.
        acceleration: acceleration limits (rad/s^2) > 0.
        jerk: jerk limits (rad/s^3) > 0, or None for acceleration-limited moves.
    """

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray | None = None

    def __post_init__(self) -> None:
        freeze_limit_arrays(self, optional=("jerk",), joints=2)

    def __repr__(self) -> str:
        jerk = None if self.jerk is None else self.jerk.tolist()
        return (f"JointLimits(lower={self.lower.tolist()}, upper={self.upper.tolist()}, "
                f"velocity={self.velocity.tolist()}, acceleration={self.acceleration.tolist()}, "
                f"jerk={jerk})")


class Arm:
    """A planar 2R arm: Pinocchio model/data, its geometry and limits.

    Build it with :func:`load_planar_arm`. Attributes: ``name``, ``model``, ``data``
    (scratch), ``tip_frame_id``, ``link_lengths`` (L1, L2), ``base_xy``,
    ``joint_limits``, ``cartesian_limits``, ``axis_signs`` (+1 if a joint turns
    counter-clockwise seen from +z), ``angle_offsets`` (geometric angles a1, a2 at
    q = 0), ``kinematics`` (the :class:`~subtask_opt.kinematics._kernels.ArmKinematics`
    the numba kernels take).
    """

    def __init__(self, model: Any, tip_frame: str, joint_limits: JointLimits,
                 cartesian_limits: CartesianLimits, name: str) -> None:
        import pinocchio as pin

        if model.nq != 2 or model.nv != 2 or model.njoints != 3:
            raise InputDataError(
                f"robot {name!r} must have exactly two revolute joints, got nq={model.nq}, "
                f"nv={model.nv}, {model.njoints - 1} joints")
        if not model.existFrame(tip_frame):
            frames = [f.name for f in model.frames]
            raise InputDataError(f"robot {name!r} has no frame {tip_frame!r}; frames: {frames}")
        self.name = name
        self.model = model
        self.data = model.createData()
        self._data_lock = threading.Lock()  # Pinocchio's data is scratch: one caller at a time
        self.tip_frame_id = int(model.getFrameId(tip_frame))
        self.joint_limits = joint_limits
        self.cartesian_limits = cartesian_limits

        q0 = np.zeros(2)
        pin.framesForwardKinematics(model, self.data, q0)
        jac = pin.computeFrameJacobian(model, self.data, q0, self.tip_frame_id,
                                       pin.LOCAL_WORLD_ALIGNED)
        signs = []
        for col in range(2):
            axis = jac[3:6, col]
            if np.linalg.norm(axis[:2]) > _AXIS_TOL or abs(abs(axis[2]) - 1) > _AXIS_TOL:
                raise InputDataError(
                    f"robot {name!r}: joint {model.names[col + 1]!r} must turn about the world "
                    f"z axis (planar arm), its axis is {axis.round(6).tolist()}")
            signs.append(1.0 if axis[2] > 0 else -1.0)
        p1 = self.data.oMi[1].translation[:2].copy()
        p2 = self.data.oMi[2].translation[:2].copy()
        tip = self.data.oMf[self.tip_frame_id]
        pt = tip.translation[:2].copy()
        l1 = float(np.linalg.norm(p2 - p1))
        l2 = float(np.linalg.norm(pt - p2))
        if l1 <= _AXIS_TOL or l2 <= _AXIS_TOL:
            raise InputDataError(
                f"robot {name!r}: link lengths in the plane must be > 0, got {l1:.6g}, {l2:.6g}")
        a1 = math.atan2(p2[1] - p1[1], p2[0] - p1[0])
        a2 = _k.wrap_angle(math.atan2(pt[1] - p2[1], pt[0] - p2[0]) - a1)
        # The tool angle is the yaw of one tip-frame axis that is not vertical.
        rot = tip.rotation
        self._yaw_column = 0 if np.linalg.norm(rot[:2, 0]) >= np.linalg.norm(rot[:2, 1]) else 1
        phi0 = self._yaw(rot)
        self.link_lengths: tuple[float, float] = (l1, l2)
        self.base_xy = p1
        self.base_xy.setflags(write=False)
        self.axis_signs = (signs[0], signs[1])
        self.angle_offsets = (a1, a2)
        lo, up = joint_limits.lower, joint_limits.upper
        self.kinematics = _k.ArmKinematics(
            base_x=float(p1[0]), base_y=float(p1[1]), l1=l1, l2=l2, a1=a1, a2=a2,
            s1=signs[0], s2=signs[1], phi_offset=_k.wrap_angle(phi0 - a1 - a2),
            lower1=float(lo[0]), lower2=float(lo[1]), upper1=float(up[0]), upper2=float(up[1]))

    def _yaw(self, rot: np.ndarray) -> float:
        col = rot[:, self._yaw_column]
        return math.atan2(col[1], col[0])

    def __repr__(self) -> str:
        l1, l2 = self.link_lengths
        return (f"Arm({self.name!r}, links=({l1:.4g}, {l2:.4g}) m, "
                f"base=({self.base_xy[0]:.4g}, {self.base_xy[1]:.4g}))")

    @property
    def r_min(self) -> float:
        """Inner radius |L1 - L2| of the reachable annulus (m), ignoring joint limits."""
        return abs(self.link_lengths[0] - self.link_lengths[1])

    @property
    def r_max(self) -> float:
        """Outer radius L1 + L2 of the reachable annulus (m)."""
        return self.link_lengths[0] + self.link_lengths[1]

    def _q(self, q: Any) -> np.ndarray:
        arr = np.asarray(q, dtype=np.float64)
        if arr.shape != (2,) or not np.all(np.isfinite(arr)):
            raise ParameterError(f"q must be 2 finite joint angles, got {q!r}")
        return arr

    def fk(self, q: Any) -> np.ndarray:
        """Tip pose (x, y, phi) by Pinocchio; phi is the yaw of the tip frame in the plane."""
        import pinocchio as pin

        q = self._q(q)
        with self._data_lock:
            pin.framesForwardKinematics(self.model, self.data, q)
            tip = self.data.oMf[self.tip_frame_id]
            return np.array([tip.translation[0], tip.translation[1], self._yaw(tip.rotation)])

    def link_points(self, q: Any) -> np.ndarray:
        """(3, 2) positions of the shoulder, the elbow and the tip at q (for drawing the arm)."""
        import pinocchio as pin

        q = self._q(q)
        with self._data_lock:
            pin.framesForwardKinematics(self.model, self.data, q)
            return np.array([self.data.oMi[1].translation[:2], self.data.oMi[2].translation[:2],
                             self.data.oMf[self.tip_frame_id].translation[:2]])

    def jacobian(self, q: Any) -> np.ndarray:
        """2x2 Jacobian d(x, y)/dq of the tip (Pinocchio frame Jacobian, LOCAL_WORLD_ALIGNED)."""
        import pinocchio as pin

        q = self._q(q)
        with self._data_lock:
            jac = pin.computeFrameJacobian(self.model, self.data, q, self.tip_frame_id,
                                           pin.LOCAL_WORLD_ALIGNED)
            return np.array(jac[:2, :2])

    def __getstate__(self) -> dict[str, Any]:
        """Pickle without the lock (a copy gets a fresh one)."""
        state = dict(vars(self))
        state.pop("_data_lock", None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        vars(self).update(state)
        self._data_lock = threading.Lock()

    def with_joint_limits(self, *, velocity: Any = None, acceleration: Any = None,
                          jerk: Any = None) -> Arm:
        """This arm with other speed, acceleration or jerk limits (a scalar or one per joint)."""
        limits = self.joint_limits

        def per_joint(name: str, value: Any, old: Any) -> Any:
            if value is None:
                return old
            arr = np.broadcast_to(np.asarray(value, dtype=float).ravel(), (2,)) \
                if np.size(value) == 1 else np.asarray(value, dtype=float)
            if arr.shape != (2,):
                raise ParameterError(f"{name} limits must be one value or 2 (one per joint), "
                                     f"got {value!r}")
            return arr.copy()
        new = JointLimits(limits.lower, limits.upper,
                          per_joint("velocity", velocity, limits.velocity),
                          per_joint("acceleration", acceleration, limits.acceleration),
                          per_joint("jerk", jerk, limits.jerk))
        return Arm(self.model, self.model.frames[self.tip_frame_id].name, new,
                   self.cartesian_limits, self.name)

    def ik(self, xy: Any) -> np.ndarray:
        """Analytic inverse kinematics of one point (2,) or of M points (M, 2).

        Returns (2, 2) for one point (row 0 elbow-down, row 1 elbow-up; each row
        (q1, q2) inside the joint limits), or (M, 2, 2) for M points. A row is NaN
        where the point is outside the annulus or the branch breaks a joint limit.
        """
        pts = np.asarray(xy, dtype=np.float64)
        single = pts.shape == (2,)
        pts2 = pts.reshape(1, 2) if single else pts
        if pts2.ndim != 2 or pts2.shape[1] != 2:
            raise ParameterError(f"xy must have shape (2,) or (M, 2), got {pts.shape}")
        q, _ = _k.ik_batch(self.kinematics, np.array(pts2, order="C"), True)
        return q[0] if single else q

    def reachable(self, xy: Any) -> bool:
        """Whether the point (x, y) is reachable in at least one elbow branch."""
        q = self.ik(xy)
        if q.ndim != 2:
            raise ParameterError(f"reachable takes one point (x, y), got shape {np.shape(xy)}")
        return bool(np.isfinite(q).all(axis=1).any())

    def check_reachable(self, points: Any) -> None:
        """Raise :class:`UnreachableError` naming the first point no branch reaches, and why."""
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise InputDataError(f"points must have shape (N, 2), got {pts.shape}")
        bad = np.flatnonzero(~np.isfinite(pts).all(axis=1))
        if bad.size:
            raise InputDataError(
                f"subtask {bad[0]} is not finite: {pts[bad[0]].tolist()}")
        q, status = _k.ik_batch(self.kinematics, np.array(pts, order="C"), False)
        for i in np.flatnonzero((status != 0).all(axis=1)):
            x, y = pts[i]
            r = math.hypot(x - self.base_xy[0], y - self.base_xy[1])
            where = f"subtask {i} at ({x:.6g}, {y:.6g})"
            if status[i, 0] == 1 and r > self.r_max:
                why = (f"is beyond the reach of {self.name}: "
                       f"r = {r:.6g} m > r_max = {self.r_max:.6g} m")
            elif status[i, 0] == 1:
                why = (f"is inside the unreachable inner disc of {self.name}: "
                       f"r = {r:.6g} m < r_min = {self.r_min:.6g} m")
            else:
                lim = self.joint_limits
                parts = []
                for br in range(2):
                    joint = int(status[i, br]) - 2
                    parts.append(
                        f"{BRANCH_NAMES[br]} needs q{joint + 1} = {q[i, br, joint]:.4g} outside "
                        f"[{lim.lower[joint]:.4g}, {lim.upper[joint]:.4g}]")
                why = (f"breaks the joint limits of {self.name} in both branches "
                       f"({'; '.join(parts)})")
            raise UnreachableError(f"{where} {why}")


def _read_params(path: Path) -> dict[str, Any]:
    params = parse_json(read_text(path, "robot parameter file", max_bytes=1 << 20),
                        f"robot parameter file {path}")
    if not isinstance(params, dict):
        raise InputDataError(f"robot parameter file {path} must hold a JSON object")
    return params


def _section(params: dict[str, Any], key: str, path: Path | None) -> dict[str, Any]:
    value = params.get(key, {})
    if not isinstance(value, dict):
        raise InputDataError(f"{key!r} in robot parameter file {path} must be a JSON object")
    return value


def load_planar_arm(name_or_path: str | Path = "planar_2r", *,
             cartesian_limits: CartesianLimits | None = None,
             joint_limits: JointLimits | None = None,
             tip_frame: str | None = None) -> Arm:
    """Load a robot by name (see :data:`ROBOT_NAMES`) or from a URDF path.

    A URDF path may have a JSON file with the same stem beside it holding
    ``tip_frame``, ``joint_limits`` (``acceleration``, ``jerk``, and optionally
    ``lower``/``upper``/``velocity`` overriding the URDF) and
    ``cartesian_limits`` (``kv``, ``ka``, ``kw``, ``kw_dot``). The keyword
    arguments replace what the files give.

    Raises:
        ParameterError: unknown robot name, or limits missing or invalid.
        InputDataError: unreadable URDF/JSON, or not a planar 2R arm.
    """
    import pinocchio as pin

    text = str(name_or_path)
    if text in ROBOT_NAMES:
        name = text
        params_path: Path | None = robots_dir() / f"{text}.json"
        if text == "asr_twodof":
            urdf = (example_robot_data_share() / "example-robot-data" / "robots"
                    / "asr_twodof_description" / "urdf" / "TwoDofs.urdf")
        else:
            urdf = robots_dir() / f"{text}.urdf"
    elif text.lower().endswith(".urdf") or Path(text).is_file():
        urdf = Path(text)
        name = urdf.stem
        params_path = urdf.with_suffix(".json")
        if not params_path.is_file():
            params_path = None
    else:
        raise ParameterError(
            f"unknown robot {text!r}: expected one of {', '.join(ROBOT_NAMES)} or a path to a "
            f".urdf file")
    check_input_file(urdf, "URDF file")  # a regular file of at most 64 MiB, never a FIFO
    params = _read_params(params_path) if params_path is not None else {}
    try:
        with quiet_stderr():  # the URDF parser prints its own 'Error:' lines; ours follows
            model = pin.buildModelFromUrdf(str(urdf))
    except (RuntimeError, ValueError) as exc:
        raise InputDataError(f"cannot build a robot model from {urdf}: {exc}") from None

    if tip_frame is None:
        tip_frame = params.get("tip_frame") or model.frames[len(model.frames) - 1].name
    if joint_limits is None:
        jl = _section(params, "joint_limits", params_path)
        if "acceleration" not in jl:
            raise ParameterError(
                f"robot {name!r} has no joint acceleration limits: give "
                f'"joint_limits": {{"acceleration": [a1, a2]}} in {urdf.with_suffix(".json").name} '
                "beside the URDF, or pass joint_limits=")
        try:
            joint_limits = JointLimits(
                lower=jl.get("lower", np.array(model.lowerPositionLimit)),
                upper=jl.get("upper", np.array(model.upperPositionLimit)),
                velocity=jl.get("velocity", np.array(model.velocityLimit)),
                acceleration=jl["acceleration"],
                jerk=jl.get("jerk"),
            )
        except ParameterError as exc:
            raise ParameterError(f"robot {name!r}: {exc}") from None
    if cartesian_limits is None:
        cl = _section(params, "cartesian_limits", params_path)
        missing_keys = [k for k in ("kv", "ka", "kw", "kw_dot") if k not in cl]
        if missing_keys:
            raise ParameterError(
                f"robot {name!r} has no Cartesian limits {', '.join(missing_keys)}: give "
                f'"cartesian_limits": {{"kv": .., "ka": .., "kw": .., "kw_dot": ..}} in '
                f"{urdf.with_suffix('.json').name} beside the URDF, or pass cartesian_limits=")
        try:
            cartesian_limits = CartesianLimits(cl["kv"], cl["ka"], cl["kw"], cl["kw_dot"])
        except ParameterError as exc:
            raise ParameterError(f"robot {name!r}: {exc}") from None
    if not isinstance(joint_limits, JointLimits):
        raise ParameterError(f"joint_limits must be a JointLimits, got {joint_limits!r}")
    if not isinstance(cartesian_limits, CartesianLimits):
        raise ParameterError(
            f"cartesian_limits must be a CartesianLimits, got {cartesian_limits!r}")
    return Arm(model, str(tip_frame), joint_limits, cartesian_limits, name)


__all__ = [
    "Arm", "BRANCH_NAMES", "CartesianLimits", "JointLimits", "ROBOT_NAMES", "load_planar_arm",
]
