"""Any serial arm: a Pinocchio model of a URDF chain with a tool frame and joint limits.

:func:`load_serial_arm` builds a :class:`SerialArm` from a robot name or a URDF
path. Names: ``ur3``, ``ur5``, ``ur10`` and ``panda`` are the URDFs of the
installed example-robot-data distribution (``ur_description/urdf/ur*_robot.urdf``
and ``panda_description/urdf/panda.urdf``, the files ``example_robot_data.load``
uses; its Python module is not needed, only its data files, and nothing is
downloaded); ``vs060_drill`` is the Denso VS060 with the RoboTSP drill shipped in
``robots/``. The panda's two finger joints are locked at 0 so the arm has its
seven joints.

Limits: position and velocity limits come from the URDF (a joint without them is
an :class:`~subtask_opt.base.errors.InputDataError` naming the joint and the
``<limit>`` attributes to add); acceleration and jerk limits, which URDF cannot
hold, come from a JSON file with the URDF's stem beside it (``robots/<name>.json``
for the shipped names), or from the ``limits`` argument. The JSON file may hold
named limit sets (``"limit_sets": {"robotsp": {...}}``) that ``limits="robotsp"``
selects; a set's arrays replace the URDF's.

The tool frame defaults to the model's last frame; ``tool_offset`` (a 4x4
homogeneous matrix, or ``(xyz, rpy)``) adds a fixed frame ``tool`` on top of it
(``tool_offset`` if the URDF already has a ``tool`` frame).

Thread safety: the model is never written after construction and every
kinematic call uses a Pinocchio ``data`` owned by the calling thread
(``threading.local``), so one :class:`SerialArm` may be shared by threads.
"""

from __future__ import annotations

import importlib.metadata
import importlib.resources
import math
import threading
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.base.files import check_input_file, parse_json, read_text
from subtask_opt.kinematics.limit_arrays import freeze_limit_arrays

SERIAL_ROBOT_NAMES: tuple[str, ...] = ("ur3", "ur5", "ur10", "panda", "vs060_drill")

# Name -> (path below example-robot-data's robots/ folder, joints locked at a value).
_ERD_ROBOTS: dict[str, tuple[str, dict[str, float]]] = {
    "ur3": ("ur_description/urdf/ur3_robot.urdf", {}),
    "ur5": ("ur_description/urdf/ur5_robot.urdf", {}),
    "ur10": ("ur_description/urdf/ur10_robot.urdf", {}),
    "panda": ("panda_description/urdf/panda.urdf",
              {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}),
}

TOOL_FRAME_NAME = "tool"
"""Name of the frame :func:`load_serial_arm` adds when a ``tool_offset`` is given
(``tool_offset``, ``tool_offset_offset``, ... if the URDF already has a frame of that name)."""


@dataclass(frozen=True, eq=False)
class SerialLimits:
    """Per-joint limits of an n-joint arm, arrays of shape (n,) in the model's joint order.

    Attributes:
        lower, upper: position limits (rad, or m for prismatic joints), lower < upper.
        velocity: speed limits > 0.
        acceleration: acceleration limits > 0, or None when no source gave them.
        jerk: jerk limits > 0, or None.
        name: where the limits came from (``"urdf"``, a limit-set name, ``"arguments"``).
    """

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray | None = None
    jerk: np.ndarray | None = None
    name: str = "urdf"

    def __post_init__(self) -> None:
        freeze_limit_arrays(self, optional=("acceleration", "jerk"))

    @property
    def n(self) -> int:
        """Number of joints."""
        return int(self.lower.size)

    def require(self, field: str) -> np.ndarray:
        """The ``acceleration`` or ``jerk`` array; InputDataError naming what to add if absent."""
        if field not in ("acceleration", "jerk"):
            raise ParameterError(f"SerialLimits.require takes 'acceleration' or 'jerk', "
                                 f"got {field!r}")
        value = getattr(self, field)
        if value is None:
            raise InputDataError(
                f"no joint {field} limits: add \"joint_limits\": {{\"{field}\": "
                f"[{', '.join(['...'] * self.n)}]}} to the JSON file beside the URDF, or pass "
                f"limits={{'{field}': [...]}}")
        return value

    def __repr__(self) -> str:
        def fmt(a: np.ndarray | None) -> Any:
            return None if a is None else a.tolist()
        return (f"SerialLimits({self.name!r}, lower={fmt(self.lower)}, upper={fmt(self.upper)}, "
                f"velocity={fmt(self.velocity)}, acceleration={fmt(self.acceleration)}, "
                f"jerk={fmt(self.jerk)})")


class SerialArm:
    """A serial arm: Pinocchio model, tool frame and limits. Build it with :func:`load_serial_arm`.

    Attributes:
        name: robot name (the URDF stem for a path).
        model: the Pinocchio model (never modified after construction).
        urdf_path: the URDF it was built from.
        package_dirs: folders that resolve ``package://`` mesh URIs of the URDF.
        locked_joints: joints removed from the URDF's chain and their fixed values.
        tool_frame: name of the tool frame; ``tool_frame_id`` its Pinocchio id.
        limits: :class:`SerialLimits`.
        joint_names: the moving joints in q order.
        revolute: boolean mask, True for revolute joints (2 pi periodic).
        nq: number of joints.
    """

    def __init__(self, *, name: str, model: Any, urdf_path: Path, package_dirs: list[str],
                 locked_joints: Mapping[str, float], tool_frame: str,
                 limits: SerialLimits) -> None:
        self.name = name
        self.model = model
        self.urdf_path = urdf_path
        self.package_dirs = list(package_dirs)
        self.locked_joints = dict(locked_joints)
        self.tool_frame = tool_frame
        self.tool_frame_id = int(model.getFrameId(tool_frame))
        self.limits = limits
        self.nq = int(model.nq)
        self.joint_names: tuple[str, ...] = tuple(model.names[i] for i in range(1, model.njoints))
        self.revolute = np.array(
            [not model.joints[i].shortname().startswith("JointModelP")
             for i in range(1, model.njoints)], dtype=bool)
        self.revolute.setflags(write=False)
        self._local = threading.local()

    def __repr__(self) -> str:
        return f"SerialArm({self.name!r}, nq={self.nq}, tool_frame={self.tool_frame!r})"

    @property
    def data(self) -> Any:
        """The calling thread's Pinocchio data (created on first use in each thread)."""
        data = getattr(self._local, "data", None)
        if data is None:
            data = self.model.createData()
            self._local.data = data
        return data

    def check_q(self, q: Any) -> np.ndarray:
        """q as a float array of shape (nq,); ParameterError if the shape is wrong or not finite."""
        arr = np.asarray(q, dtype=np.float64)
        if arr.shape != (self.nq,) or not np.all(np.isfinite(arr)):
            raise ParameterError(
                f"q must be {self.nq} finite joint values for {self.name}, got {q!r}")
        return arr

    def within_limits(self, q: Any, tol: float = 1e-9) -> bool:
        """Whether every joint of q lies in [lower - tol, upper + tol]."""
        q = self.check_q(q)
        return bool(np.all(q >= self.limits.lower - tol) and np.all(q <= self.limits.upper + tol))

    def fk_se3(self, q: Any, frame_id: int | None = None) -> Any:
        """Pose of the tool frame (or of ``frame_id``) in the model's world frame, a pin.SE3."""
        import pinocchio as pin

        q = self.check_q(q)
        data = self.data
        pin.forwardKinematics(self.model, data, q)
        fid = self.tool_frame_id if frame_id is None else frame_id
        return pin.updateFramePlacement(self.model, data, fid).copy()

    def fk(self, q: Any) -> np.ndarray:
        """Tool pose at q as a 4x4 homogeneous matrix (Pinocchio forward kinematics)."""
        return np.array(self.fk_se3(q).homogeneous)

    def jacobian(self, q: Any) -> np.ndarray:
        """6 x nq tool-frame Jacobian in the LOCAL frame (linear rows first)."""
        import pinocchio as pin

        q = self.check_q(q)
        return np.array(pin.computeFrameJacobian(self.model, self.data, q, self.tool_frame_id,
                                                 pin.LOCAL))

    def frame_names(self) -> list[str]:
        """Names of every frame of the model (candidates for ``tool_frame``)."""
        return [f.name for f in self.model.frames]


def robots_dir() -> Path:
    """The folder of URDFs and limit files shipped with subtask_opt."""
    return Path(str(importlib.resources.files("subtask_opt.robots")))


def example_robot_data_share() -> Path:
    """The installed example-robot-data ``share`` folder (resolves its package:// URIs)."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        raise InputDataError("robots asr_twodof, ur3, ur5, ur10 and panda need the "
                             "example-robot-data package (pip install example-robot-data)") \
            from None
    share = Path(str(dist.locate_file("cmeel.prefix/share")))
    if not (share / "example-robot-data" / "robots").is_dir():
        raise InputDataError(f"example-robot-data's robots folder not found under {share}")
    return share


def _pose_matrix(owner: str, value: Any) -> np.ndarray:
    """A 4x4 rigid transform from a 4x4 array or an (xyz, rpy) pair."""
    import pinocchio as pin

    arr: np.ndarray
    if isinstance(value, (tuple, list)) and len(value) == 2:
        try:
            xyz = np.array(value[0], dtype=np.float64)
            rpy = np.array(value[1], dtype=np.float64)
        except (TypeError, ValueError):
            raise ParameterError(f"{owner} must be a 4x4 matrix or (xyz, rpy), "
                                 f"got {value!r}") from None
        if xyz.shape != (3,) or rpy.shape != (3,):
            raise ParameterError(f"{owner} as (xyz, rpy) needs 3 + 3 numbers, got {value!r}")
        arr = np.eye(4)
        arr[:3, :3] = pin.rpy.rpyToMatrix(*rpy)
        arr[:3, 3] = xyz
    else:
        try:
            arr = np.array(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise ParameterError(f"{owner} must be a 4x4 matrix or (xyz, rpy), "
                                 f"got {value!r}") from None
        if arr.shape != (4, 4):
            raise ParameterError(f"{owner} must be a 4x4 matrix or (xyz, rpy), "
                                 f"got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{owner} must be finite, got {arr.tolist()}")
    rot = arr[:3, :3]
    if (np.abs(rot.T @ rot - np.eye(3)).max() > 1e-6 or abs(np.linalg.det(rot) - 1) > 1e-6
            or np.abs(arr[3] - [0, 0, 0, 1]).max() > 1e-12):
        raise ParameterError(f"{owner} must be a rigid transform (rotation block orthonormal "
                             f"with det +1, last row 0 0 0 1), got {arr.tolist()}")
    return arr


def _check_urdf_limits(urdf: Path, locked: Mapping[str, float]) -> None:
    """Raise one InputDataError naming every moving joint whose <limit> is missing or empty."""
    try:
        root = ET.parse(urdf).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputDataError(f"cannot read URDF {urdf}: {exc}") from None
    problems: list[str] = []
    for joint in root.findall("joint"):
        jname = joint.get("name", "?")
        jtype = joint.get("type", "?")
        if jtype in ("fixed", "floating", "planar") or jname in locked:
            continue
        if jtype == "continuous":
            problems.append(f"joint {jname!r} is continuous: make it revolute with "
                            '<limit lower="..." upper="..." velocity="..." effort="..."/>')
            continue
        limit = joint.find("limit")
        missing = [] if limit is not None else ["lower", "upper", "velocity"]
        if limit is not None:
            for attr in ("lower", "upper", "velocity"):
                text = limit.get(attr)
                try:
                    ok = text is not None and math.isfinite(float(text))
                except ValueError:
                    ok = False
                if not ok or (attr == "velocity" and float(text or 0) <= 0):
                    missing.append(attr)
            if not missing and float(limit.get("lower", 0)) >= float(limit.get("upper", 0)):
                missing = ["lower < upper"]
        if missing:
            problems.append(f"joint {jname!r} ({jtype}) needs <limit> with "
                            f"{', '.join(missing)}")
    if problems:
        raise InputDataError(f"URDF {urdf} lacks joint limits: {'; '.join(problems)}")


def _read_json(path: Path) -> dict[str, Any]:
    text = read_text(path, "robot parameter file", max_bytes=1 << 20)
    params = parse_json(text, f"robot parameter file {path}")  # depth-limited
    if not isinstance(params, dict):
        raise InputDataError(f"robot parameter file {path} must hold a JSON object")
    return params


def _limit_overrides(params: dict[str, Any], limits: Any, path: Path | None) -> tuple[
        dict[str, Any], str]:
    """The per-joint arrays that replace or complete the URDF's, and the set's name."""
    base = params.get("joint_limits", {})
    if not isinstance(base, dict):
        raise InputDataError(f"'joint_limits' in {path} must be a JSON object")
    values = dict(base)
    name = "urdf"
    if limits is None:
        return values, name
    if isinstance(limits, str):
        sets = params.get("limit_sets", {})
        if not isinstance(sets, dict) or limits not in sets:
            available = sorted(sets) if isinstance(sets, dict) else []
            raise ParameterError(f"unknown limit set {limits!r}: {path} defines "
                                 f"{available or 'none'}")
        chosen = sets[limits]
        if not isinstance(chosen, dict):
            raise InputDataError(f"limit set {limits!r} in {path} must be a JSON object")
        values.update({k: v for k, v in chosen.items() if k != "description"})
        return values, limits
    if isinstance(limits, Mapping):
        values.update(limits)
        return values, "arguments"
    raise ParameterError(f"limits must be None, a limit-set name, a mapping or SerialLimits, "
                         f"got {limits!r}")


def load_serial_arm(name_or_urdf: str | Path, *, tool_frame: str | None = None,
                    tool_offset: Any = None, limits: Any = None) -> SerialArm:
    """Load a serial arm by name (:data:`SERIAL_ROBOT_NAMES`) or from a URDF path.

    Args:
        name_or_urdf: a robot name or a ``.urdf`` path (a JSON file with the same stem
            beside it may hold ``tool_frame``, ``joint_limits`` and ``limit_sets``).
        tool_frame: frame whose pose FK and IK use; default the JSON's ``tool_frame``,
            else the model's last frame.
        tool_offset: optional fixed transform from ``tool_frame`` to the tool, a 4x4
            matrix or ``(xyz, rpy)`` (metres, radians); adds the frame ``tool``.
        limits: None (URDF + JSON ``joint_limits``), the name of a JSON limit set, a
            mapping of per-joint arrays (``lower``, ``upper``, ``velocity``,
            ``acceleration``, ``jerk``) replacing those of the files, or a
            :class:`SerialLimits`.

    Raises:
        ParameterError: unknown name, bad ``tool_offset`` or ``limits``.
        InputDataError: unreadable URDF/JSON, missing joint limits, unknown tool frame,
            a joint that is neither revolute nor prismatic.
    """
    import pinocchio as pin

    text = str(name_or_urdf)
    locked: dict[str, float] = {}
    package_dirs: list[str] = []
    params_path: Path | None
    if text in _ERD_ROBOTS:
        share = example_robot_data_share()
        rel, locked = _ERD_ROBOTS[text]
        urdf = share / "example-robot-data" / "robots" / rel
        package_dirs = [str(share)]
        params_path = robots_dir() / f"{text}.json"
        name = text
    elif text in SERIAL_ROBOT_NAMES:
        urdf = robots_dir() / f"{text}.urdf"
        params_path = urdf.with_suffix(".json")
        name = text
    elif text.lower().endswith(".urdf") or Path(text).is_file():
        urdf = Path(text)
        params_path = urdf.with_suffix(".json")
        # package:// URIs resolve in the URDF's folder, or in the installed robot
        # descriptions of example-robot-data (a copied UR or Panda URDF keeps its meshes)
        package_dirs = [str(urdf.parent)]
        try:
            package_dirs.append(str(example_robot_data_share()))
        except InputDataError:
            pass
        name = urdf.stem
    else:
        raise ParameterError(f"unknown robot {text!r}: expected one of "
                             f"{', '.join(SERIAL_ROBOT_NAMES)} or a path to a .urdf file")
    check_input_file(urdf, "URDF file")  # a regular file of at most 64 MiB, never a FIFO
    params = _read_json(params_path) if params_path is not None and params_path.is_file() else {}
    _check_urdf_limits(urdf, locked)
    try:
        full = pin.buildModelFromUrdf(str(urdf))
    except (RuntimeError, ValueError) as exc:
        raise InputDataError(f"cannot build a robot model from {urdf}: {exc}") from None
    if locked:
        q_ref = pin.neutral(full)
        ids = []
        for jname, value in locked.items():
            jid = full.getJointId(jname)
            q_ref[full.idx_qs[jid]] = value
            ids.append(jid)
        model = pin.buildReducedModel(full, ids, q_ref)
    else:
        model = full
    for i in range(1, model.njoints):
        short = model.joints[i].shortname()
        if model.joints[i].nq != 1 or model.joints[i].nv != 1 or not (
                short.startswith("JointModelR") or short.startswith("JointModelP")):
            raise InputDataError(f"robot {name!r}: joint {model.names[i]!r} is {short}; only "
                                 "revolute and prismatic joints are supported")
    if model.nq == 0:
        raise InputDataError(f"robot {name!r} has no moving joint")

    if tool_frame is None:
        tool_frame = params.get("tool_frame") or model.frames[len(model.frames) - 1].name
    if (not isinstance(tool_frame, str) or not tool_frame.isprintable()
            or not tool_frame.encode("utf-8", "replace").decode() == tool_frame
            or not model.existFrame(tool_frame)):
        available = [f.name for f in model.frames]
        raise InputDataError(f"robot {name!r} has no frame {tool_frame!r}; available frames: "
                             f"{', '.join(available)}")
    if model.frames[model.getFrameId(tool_frame)].parentJoint == 0:  # e.g. "universe"
        moving = [f.name for f in model.frames if f.parentJoint > 0]
        raise InputDataError(f"robot {name!r}: the tool frame {tool_frame!r} is fixed to the "
                             f"base (no joint moves it); choose a frame on the arm, e.g. "
                             f"{', '.join(moving[-3:])}")
    if tool_offset is not None:
        offset = pin.SE3(_pose_matrix("tool_offset", tool_offset))
        parent_id = model.getFrameId(tool_frame)
        parent = model.frames[parent_id]
        new_name = TOOL_FRAME_NAME
        while model.existFrame(new_name):  # the URDF has its own "tool" frame
            new_name += "_offset"
        model.addFrame(pin.Frame(new_name, parent.parentJoint, parent_id,
                                 parent.placement * offset, pin.FrameType.OP_FRAME))
        tool_frame = new_name

    if isinstance(limits, SerialLimits):
        serial_limits = limits
    else:
        values, set_name = _limit_overrides(params, limits, params_path)
        try:
            serial_limits = SerialLimits(
                lower=values.get("lower", np.array(model.lowerPositionLimit)),
                upper=values.get("upper", np.array(model.upperPositionLimit)),
                velocity=values.get("velocity", np.array(model.velocityLimit)),
                acceleration=values.get("acceleration"),
                jerk=values.get("jerk"),
                name=set_name,
            )
        except ParameterError as exc:
            raise ParameterError(f"robot {name!r}: {exc}") from None
    if serial_limits.n != model.nq:
        raise ParameterError(f"robot {name!r} has {model.nq} joints but the limits have "
                             f"{serial_limits.n}")
    return SerialArm(name=name, model=model, urdf_path=urdf, package_dirs=package_dirs,
                     locked_joints=locked, tool_frame=tool_frame, limits=serial_limits)


def pose_error(target: np.ndarray, reached: np.ndarray) -> tuple[float, float]:
    """(position error in m, rotation error in rad) between two 4x4 poses."""
    dp = float(np.linalg.norm(np.asarray(target)[:3, 3] - np.asarray(reached)[:3, 3]))
    rel = np.asarray(target)[:3, :3].T @ np.asarray(reached)[:3, :3]
    cos = min(1.0, max(-1.0, (float(np.trace(rel)) - 1.0) / 2.0))
    angle = math.acos(cos)
    if angle < 1e-4:  # acos loses precision near 0; use the skew part instead
        skew = np.array([rel[2, 1] - rel[1, 2], rel[0, 2] - rel[2, 0], rel[1, 0] - rel[0, 1]])
        angle = float(np.linalg.norm(skew)) / 2.0
    return dp, angle


def as_pose_array(poses: Sequence[Any] | np.ndarray) -> np.ndarray:
    """Stack 4x4 poses into an (m, 4, 4) float array (accepts one 4x4)."""
    arr = np.asarray(poses, dtype=np.float64)
    if arr.shape == (4, 4):
        arr = arr[None]
    if arr.ndim != 3 or arr.shape[1:] != (4, 4):
        raise ParameterError(f"poses must be 4x4 matrices, got shape {arr.shape}")
    return arr
