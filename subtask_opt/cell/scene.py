"""Collision checking of a serial arm against a cell and itself (Pinocchio + coal).

A :class:`Scene` is read from JSON (version 2; a version-1 file, boxes only, is one)::

    {"boxes":  [{"name": "table", "center": [x, y, z], "half_extents": [a, b, c],
                 "rotation": [[...], [...], [...]]}],
     "meshes": [{"name": "part", "file": "part.stl", "scale": 1.0,
                 "position": [x, y, z], "rotation": [[...], [...], [...]]}],
     "tool":   {"frame": "tool0", "tcp": {"xyz": [0, 0, 0.15], "rpy": [0, 0, 0]},
                "boxes": [...], "meshes": [...]},
     "note":   "free text"}

Every key is optional but the document needs one of ``boxes``, ``meshes``, ``tool``.
``rotation`` is optional everywhere: a 3x3 matrix whose columns are the object's axes in
its frame (the robot's base; the tool's frame for the tool's parts). Mesh files (STL, OBJ,
DAE: whatever coal's ``MeshLoader`` reads, :mod:`subtask_opt.cell.meshes` for the limits)
are paths relative to the scene file's folder, which they may not leave; ``scale`` is a
number or three. ``note`` is free text, never read (the only key that means nothing);
any other unknown key, at any level, is refused with one line naming it, as are missing
files, non-orthonormal rotations and degenerate or huge meshes. :meth:`Scene.load` of a
bare mesh file (``.stl``, ``.obj``, ``.dae``, ...) is a scene with that one mesh at the
origin. Lengths in m.

The ``tool`` attaches geometry to a robot frame (poses relative to that frame) and
defines the TCP, the point and axes that reach the targets (``tcp``: ``xyz`` in m,
``rpy`` in rad, roll-pitch-yaw about the frame's fixed x, y, z axes, as in a URDF):
:meth:`Tool.mount` gives the arm whose tool frame is the TCP, so IK puts the TCP on every
target and a standoff backs it off along the TCP's own z axis
(:class:`~subtask_opt.arm.serial_problem.SerialProblem` mounts a scene's tool itself).

:meth:`Scene.for_arm` binds it to a :class:`~subtask_opt.kinematics.serial.SerialArm`
as a :class:`CollisionChecker`. The robot's geometry is the URDF's collision
geometry (meshes resolved through the arm's package folders); a URDF with no
collision geometry gets one capsule per link instead, from each joint origin to
the next (radius ``link_radius``), and, unless the scene's tool has geometry of its
own, a tool capsule from the last joint to the tool point (radius ``tool_radius``,
ending one radius short so its surface just reaches the tool point). Base-fixed
geometry is checked for self-collision only (it cannot move relative to the scene).

Self-collision pairs: every pair of robot geometries except those on the same
joint, on a joint and its parent, those already touching at the reference
configuration (every joint at 0, clipped into its limits), the "adjacent" and
"default" rules of MoveIt's setup assistant, and those the robot's SRDF disables
where one lies beside the URDF (``srdf/<name>.srdf`` of example-robot-data).
The tool's geometry is checked against the scene and against every robot link but the
one it is mounted on (and any it touches at the reference configuration).

Leg checks: :meth:`CollisionChecker.leg_in_collision` tests the straight joint
line q0 -> q1 at ``n + 1`` evenly spaced configurations with
``n = ceil(sum_j R_j |q1_j - q0_j| / clearance)``, where R_j bounds the distance
from joint j's axis to any point of the geometry it carries, the tool included (for
a revolute joint; 1 for a prismatic one). Between consecutive samples no point of the
robot moves more than ``clearance``, so a collision the samples miss is one no deeper
than ``clearance`` (the bound is tested).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError, require_in_range
from subtask_opt.base.files import parse_json, read_text
from subtask_opt.cell.meshes import Mesh, check_rotation
from subtask_opt.kinematics.serial import SerialArm

MAX_SCENE_BYTES = 8 * 1024 * 1024
_ROT_TOL = 1e-6


def _vector(label: str, value: Any, *, positive: bool = False) -> np.ndarray:
    if (not isinstance(value, list) or len(value) != 3 or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
        raise InputDataError(f"{label} must be 3 numbers, got {value!r}")
    arr = np.array(value, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        raise InputDataError(f"{label} must be finite, got {value!r}")
    if positive and np.any(arr <= 0):
        raise InputDataError(f"{label} must be 3 numbers > 0, got {value!r}")
    return arr


@dataclass(frozen=True, eq=False)
class Box:
    """One box obstacle in the robot's base frame.

    Attributes:
        name: label (unique within a scene).
        center: (3,) centre (m).
        half_extents: (3,) half sizes along the box axes (m), > 0.
        rotation: 3x3 rotation, columns = box axes in the base frame.
    """

    name: str
    center: np.ndarray
    half_extents: np.ndarray
    rotation: np.ndarray

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError(f"Box.name must be a non-empty string, got {self.name!r}")
        for field, shape in (("center", (3,)), ("half_extents", (3,)), ("rotation", (3, 3))):
            arr = np.array(getattr(self, field), dtype=np.float64)
            if arr.shape != shape or not np.all(np.isfinite(arr)):
                raise ParameterError(f"Box {self.name!r}: {field} must be finite with shape "
                                     f"{shape}, got {getattr(self, field)!r}")
            arr.setflags(write=False)
            object.__setattr__(self, field, arr)
        if np.any(self.half_extents <= 0):
            raise ParameterError(f"Box {self.name!r}: half_extents must be > 0, "
                                 f"got {self.half_extents.tolist()}")
        rot = self.rotation
        if (np.abs(rot.T @ rot - np.eye(3)).max() > _ROT_TOL
                or abs(np.linalg.det(rot) - 1.0) > _ROT_TOL):
            raise ParameterError(f"Box {self.name!r}: rotation must be orthonormal with "
                                 f"det +1, got {rot.tolist()}")

    def contains(self, point: Any) -> bool:
        """Whether a point (base frame) lies inside or on the box."""
        local = self.rotation.T @ (np.asarray(point, dtype=np.float64) - self.center)
        return bool(np.all(np.abs(local) <= self.half_extents))


@dataclass(frozen=True, eq=False)
class Tool:
    """Geometry mounted on a robot frame, and the tool centre point (TCP).

    Attributes:
        frame: the robot frame the tool is mounted on (e.g. ``tool0``).
        tcp: 4x4 pose of the TCP in ``frame`` (identity: the frame itself).
        boxes: boxes in ``frame`` (their ``center``/``rotation`` relative to it).
        meshes: meshes in ``frame``.
    """

    frame: str
    tcp: Any = None
    boxes: tuple[Box, ...] = ()
    meshes: tuple[Mesh, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.frame, str) or not self.frame:
            raise ParameterError(f"Tool.frame must be a non-empty string, got {self.frame!r}")
        tcp = np.eye(4) if self.tcp is None else np.array(self.tcp, dtype=np.float64)
        if (tcp.shape != (4, 4) or not np.all(np.isfinite(tcp))
                or np.abs(tcp[3] - [0, 0, 0, 1]).max() > 0
                or np.abs(tcp[:3, :3].T @ tcp[:3, :3] - np.eye(3)).max() > _ROT_TOL
                or abs(np.linalg.det(tcp[:3, :3]) - 1.0) > _ROT_TOL):
            raise ParameterError(f"Tool.tcp must be a 4x4 rigid transform, got {self.tcp!r}")
        tcp.setflags(write=False)
        object.__setattr__(self, "tcp", tcp)
        _check_parts("Tool", self.boxes, self.meshes)
        object.__setattr__(self, "boxes", tuple(self.boxes))
        object.__setattr__(self, "meshes", tuple(self.meshes))

    @property
    def has_geometry(self) -> bool:
        """Whether the tool has boxes or meshes of its own."""
        return bool(self.boxes or self.meshes)

    def mount(self, arm: SerialArm) -> SerialArm:
        """``arm`` with a new tool frame at the TCP (child of :attr:`frame`).

        Raises:
            InputDataError: the arm has no frame :attr:`frame`, or it is fixed to the base.
        """
        import pinocchio as pin

        model = arm.model
        if not model.existFrame(self.frame):
            names = [f.name for f in model.frames if f.parentJoint > 0]
            raise InputDataError(f"the scene's tool frame {self.frame!r} is not a frame of "
                                 f"{arm.name}; frames on the arm: {', '.join(names[-6:])}")
        parent_id = int(model.getFrameId(self.frame))
        parent = model.frames[parent_id]
        if parent.parentJoint == 0:
            raise InputDataError(f"the scene's tool frame {self.frame!r} is fixed to the base "
                                 f"of {arm.name}; mount the tool on a frame the arm moves")
        model = pin.Model(model)  # a copy: the arm given keeps its frames
        name = TCP_FRAME_NAME
        while model.existFrame(name):
            name += "_"
        model.addFrame(pin.Frame(name, parent.parentJoint, parent_id,
                                 parent.placement * pin.SE3(self.tcp), pin.FrameType.OP_FRAME))
        return SerialArm(name=arm.name, model=model, urdf_path=arm.urdf_path,
                         package_dirs=arm.package_dirs, locked_joints=arm.locked_joints,
                         tool_frame=name, limits=arm.limits)


TCP_FRAME_NAME = "tcp"
"""Name of the frame :meth:`Tool.mount` adds (``tcp_``, ... if the model has one)."""


def _check_parts(owner: str, boxes: Any, meshes: Any) -> None:
    if not all(isinstance(b, Box) for b in boxes):
        raise ParameterError(f"{owner}.boxes must hold Box objects")
    if not all(isinstance(m, Mesh) for m in meshes):
        raise ParameterError(f"{owner}.meshes must hold Mesh objects")
    for what, items in (("boxes", boxes), ("meshes", meshes)):
        names = [b.name for b in items]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ParameterError(f"{owner}.{what}: names must be unique, repeated: {dup}")


MESH_SUFFIXES = (".stl", ".obj", ".dae", ".ply", ".off", ".3ds", ".fbx", ".gltf", ".glb")
"""File suffixes :meth:`Scene.load` reads as a bare mesh rather than a JSON scene."""
_TOP_KEYS = ("boxes", "meshes", "tool", "note")
_BOX_KEYS = ("name", "center", "half_extents", "rotation")
_MESH_KEYS = ("name", "file", "scale", "position", "rotation")
_TOOL_KEYS = ("frame", "tcp", "boxes", "meshes")


def _refuse_unknown(label: str, item: dict[str, Any], allowed: tuple[str, ...]) -> None:
    unknown = sorted(set(item) - set(allowed))
    if unknown:
        raise InputDataError(f"{label} has unknown field(s) {unknown}; allowed: "
                             f"{', '.join(allowed)}")


def _list_of_objects(label: str, doc: dict[str, Any], key: str) -> list[dict[str, Any]]:
    items = doc.get(key, [])
    if not isinstance(items, list):
        raise InputDataError(f"{label}: {key!r} must be a list, got {type(items).__name__}")
    for i, item in enumerate(items):
        if not isinstance(item, dict):
            raise InputDataError(f"{label}: {key}[{i}] must be an object")
    return items


def _parse_box(label: str, item: dict[str, Any], i: int) -> Box:
    _refuse_unknown(label, item, _BOX_KEYS)
    for key in ("center", "half_extents"):
        if key not in item:
            raise InputDataError(f"{label} lacks the field {key!r}")
    name = item.get("name", f"box{i}")
    if not isinstance(name, str) or not name:
        raise InputDataError(f"{label}.name must be a non-empty string, got {name!r}")
    center = _vector(f"{label}.center", item["center"])
    half = _vector(f"{label}.half_extents", item["half_extents"], positive=True)
    rot = np.eye(3)
    if item.get("rotation") is not None:
        rot = check_rotation(f"{label}.rotation", item["rotation"])
    return Box(name=name, center=center, half_extents=half, rotation=rot)


def _parse_mesh(label: str, item: dict[str, Any], i: int, folder: Path | None) -> Mesh:
    _refuse_unknown(label, item, _MESH_KEYS)
    if "file" not in item:
        raise InputDataError(f"{label} lacks the field 'file'")
    name = item.get("name", f"mesh{i}")
    if not isinstance(name, str) or not name:
        raise InputDataError(f"{label}.name must be a non-empty string, got {name!r}")
    file = item["file"]
    if not isinstance(file, str) or not file or "\x00" in file:
        raise InputDataError(f"{label}.file must be a path, got {file!r}")
    if "://" in file or Path(file).is_absolute():
        raise InputDataError(f"{label}.file {file!r} is refused: mesh files are paths "
                             "relative to the scene file's folder")
    base = (folder if folder is not None else Path.cwd()).resolve()
    path = (base / file).resolve()
    if not path.is_relative_to(base):
        raise InputDataError(f"{label}.file {file!r} leaves the scene file's folder {base}")
    if not path.exists():
        raise InputDataError(f"{label}.file: mesh file not found: {base / file}")
    scale = item.get("scale", 1.0)
    if isinstance(scale, list):
        scale_ok = len(scale) == 3 and all(isinstance(v, (int, float)) and not isinstance(
            v, bool) for v in scale)
    else:
        scale_ok = isinstance(scale, (int, float)) and not isinstance(scale, bool)
    if not scale_ok or not np.all(np.isfinite(scale)) or np.any(np.asarray(scale) <= 0):
        raise InputDataError(f"{label}.scale must be a number > 0 or three, got {scale!r}")
    position = (_vector(f"{label}.position", item["position"]) if "position" in item
                else np.zeros(3))
    rot = np.eye(3)
    if item.get("rotation") is not None:
        rot = check_rotation(f"{label}.rotation", item["rotation"])
    try:
        return Mesh(name=name, file=path, scale=scale, position=position, rotation=rot)
    except InputDataError as exc:
        raise InputDataError(f"{label}: {exc}") from None


def _parse_tcp(label: str, value: Any) -> np.ndarray:
    import pinocchio as pin

    if not isinstance(value, dict):
        raise InputDataError(f"{label} must be an object {{\"xyz\": [...], \"rpy\": [...]}}, "
                             f"got {value!r}")
    _refuse_unknown(label, value, ("xyz", "rpy"))
    xyz = _vector(f"{label}.xyz", value["xyz"]) if "xyz" in value else np.zeros(3)
    rpy = _vector(f"{label}.rpy", value["rpy"]) if "rpy" in value else np.zeros(3)
    if np.abs(rpy).max() > 4 * math.pi:
        raise InputDataError(f"{label}.rpy must be angles in radians within "
                             f"[-4 pi, 4 pi], got {rpy.tolist()}")
    tcp = np.eye(4)
    tcp[:3, :3] = pin.rpy.rpyToMatrix(*rpy)
    tcp[:3, 3] = xyz
    return tcp


@dataclass(frozen=True, eq=False)
class Scene:
    """The cell around an arm: boxes and meshes in its base frame, and an optional tool.

    Build it with :meth:`load` or :meth:`from_dict` (or directly from :class:`Box`,
    :class:`~subtask_opt.cell.meshes.Mesh` and :class:`Tool` objects).
    """

    boxes: tuple[Box, ...] = ()
    meshes: tuple[Mesh, ...] = ()
    tool: Tool | None = None

    def __post_init__(self) -> None:
        _check_parts("Scene", self.boxes, self.meshes)
        if self.tool is not None and not isinstance(self.tool, Tool):
            raise ParameterError(f"Scene.tool must be a Tool or None, got "
                                 f"{type(self.tool).__name__}")
        object.__setattr__(self, "boxes", tuple(self.boxes))
        object.__setattr__(self, "meshes", tuple(self.meshes))

    @classmethod
    def from_dict(cls, doc: Any, source: str = "scene", folder: str | Path | None = None
                  ) -> Scene:
        """A scene from a parsed JSON document; InputDataError naming the bad field.

        ``folder``: where relative mesh paths start (default the current folder).
        """
        if not isinstance(doc, dict) or not any(k in doc for k in ("boxes", "meshes", "tool")):
            raise InputDataError(f"{source} must be a JSON object with 'boxes', 'meshes' "
                                 "and/or 'tool'")
        _refuse_unknown(source, doc, _TOP_KEYS)
        if "note" in doc and not isinstance(doc["note"], str):
            raise InputDataError(f"{source}: 'note' must be a string (free text), got "
                                 f"{type(doc['note']).__name__}")
        where = Path(folder) if folder is not None else None
        boxes = [_parse_box(f"{source}: boxes[{i}]", item, i)
                 for i, item in enumerate(_list_of_objects(source, doc, "boxes"))]
        meshes = [_parse_mesh(f"{source}: meshes[{i}]", item, i, where)
                  for i, item in enumerate(_list_of_objects(source, doc, "meshes"))]
        tool = None
        if "tool" in doc:
            spec = doc["tool"]
            label = f"{source}: tool"
            if not isinstance(spec, dict):
                raise InputDataError(f"{label} must be an object")
            _refuse_unknown(label, spec, _TOOL_KEYS)
            frame = spec.get("frame")
            if not isinstance(frame, str) or not frame or not frame.isprintable():
                raise InputDataError(f"{label}.frame must name a robot frame, got {frame!r}")
            tcp = _parse_tcp(f"{label}.tcp", spec["tcp"]) if "tcp" in spec else np.eye(4)
            tool_boxes = [_parse_box(f"{label}.boxes[{i}]", item, i)
                          for i, item in enumerate(_list_of_objects(label, spec, "boxes"))]
            tool_meshes = [_parse_mesh(f"{label}.meshes[{i}]", item, i, where)
                           for i, item in enumerate(_list_of_objects(label, spec, "meshes"))]
            try:
                tool = Tool(frame=frame, tcp=tcp, boxes=tuple(tool_boxes),
                            meshes=tuple(tool_meshes))
            except ParameterError as exc:
                raise InputDataError(f"{source}: {exc}") from None
        try:
            return cls(boxes=tuple(boxes), meshes=tuple(meshes), tool=tool)
        except ParameterError as exc:
            raise InputDataError(f"{source}: {exc}") from None

    @classmethod
    def load(cls, path: str | Path) -> Scene:
        """Read a scene JSON file (UTF-8, BOM accepted, at most 8 MiB), or a bare mesh file
        (a suffix of :data:`MESH_SUFFIXES`) as a scene of that one mesh at the origin."""
        path = Path(path)
        if path.suffix.lower() in MESH_SUFFIXES:
            return cls(meshes=(Mesh(name=path.stem or "mesh", file=path),))
        text = read_text(path, "scene file", max_bytes=MAX_SCENE_BYTES)  # regular files only
        doc = parse_json(text, f"scene file {path}")  # depth-limited: no RecursionError
        return cls.from_dict(doc, source=f"scene file {path.name}", folder=path.parent)

    def for_arm(self, arm: SerialArm, **kwargs: Any) -> CollisionChecker:
        """A :class:`CollisionChecker` of ``arm`` in this scene (kwargs as its constructor)."""
        return CollisionChecker(arm, self, **kwargs)


def _capsule_placement(start: np.ndarray, end: np.ndarray) -> tuple[Any, float]:
    """SE3 placing a z-aligned capsule on the segment start-end, and its half length.

    (coal.Capsule takes the full length: ``coal.Capsule(radius, 2 * half)``.)
    """
    import pinocchio as pin

    vec = end - start
    length = float(np.linalg.norm(vec))
    rot = np.eye(3)
    if length > 1e-12:
        z = vec / length
        ref = np.eye(3)[int(np.argmin(np.abs(z)))]
        x = ref - (ref @ z) * z
        x /= np.linalg.norm(x)
        rot = np.column_stack([x, np.cross(z, x), z])
    return pin.SE3(rot, (start + end) / 2.0), length / 2.0


class CollisionChecker:
    """Self- and box collisions of one arm; thread-safe (per-thread Pinocchio data).

    Args:
        arm: the arm.
        scene: the boxes (None: self-collision only).
        link_radius: capsule radius (m) of links when the URDF has no collision geometry.
        tool_radius: radius (m) of the tool capsule in that case.
        margin: security margin (m): pairs closer than this count as colliding.
        self_collision: check robot-robot pairs.
    """

    def __init__(self, arm: SerialArm, scene: Scene | None = None, *,
                 link_radius: float = 0.04, tool_radius: float = 0.015,
                 margin: float = 0.0, self_collision: bool = True) -> None:
        import pinocchio as pin

        require_in_range("CollisionChecker", "link_radius", link_radius, 1e-4, 10.0)
        require_in_range("CollisionChecker", "tool_radius", tool_radius, 1e-4, 10.0)
        require_in_range("CollisionChecker", "margin", margin, 0.0, 10.0)
        if not isinstance(self_collision, bool):
            raise ParameterError(f"CollisionChecker.self_collision must be a bool, got "
                                 f"{self_collision!r}")
        self.arm = arm
        self.scene = scene if scene is not None else Scene()
        self.margin = float(margin)
        model = arm.model
        tool = self.scene.tool
        geom = self._urdf_geometry()
        self.uses_capsules = geom.ngeoms == 0
        if self.uses_capsules:
            geom = self._capsule_geometry(link_radius, tool_radius,
                                          tool is None or not tool.has_geometry)
        robot_ids = list(range(geom.ngeoms))
        tool_ids = [geom.addGeometryObject(obj) for obj in self._tool_objects()]
        box_ids = []
        for box in self.scene.boxes:
            obj = pin.GeometryObject(f"box:{box.name}", 0, 0, pin.SE3(box.rotation, box.center),
                                     _coal_box(2.0 * box.half_extents))
            box_ids.append(geom.addGeometryObject(obj))
        for mesh in self.scene.meshes:
            obj = pin.GeometryObject(f"mesh:{mesh.name}", 0, 0,
                                     pin.SE3(mesh.rotation, mesh.position), mesh.geometry)
            box_ids.append(geom.addGeometryObject(obj))
        self.geometry_model = geom
        self.robot_geometry_names = [geom.geometryObjects[i].name for i in robot_ids]
        self.tool_geometry_names = [geom.geometryObjects[i].name for i in tool_ids]

        parents = model.parents
        q_ref = np.clip(np.zeros(arm.nq), arm.limits.lower, arm.limits.upper)
        ref_data = model.createData()
        pin.forwardKinematics(model, ref_data, q_ref)
        pairs: list[tuple[int, int]] = []
        if self_collision:
            for a in robot_ids:
                for b in robot_ids:
                    if b <= a:
                        continue
                    ja = geom.geometryObjects[a].parentJoint
                    jb = geom.geometryObjects[b].parentJoint
                    if ja == jb or parents[ja] == jb or parents[jb] == ja:
                        continue
                    if self._pair_collides(ref_data, a, b):
                        continue
                    pairs.append((a, b))
        if self_collision:
            srdf_off = self._srdf_disabled()
            pairs = [(a, b) for a, b in pairs
                     if frozenset((self._link_of(a), self._link_of(b))) not in srdf_off]
            # the tool against every robot link but the one it is mounted on
            for a in tool_ids:
                for b in robot_ids:
                    if geom.geometryObjects[b].parentJoint == geom.geometryObjects[a].parentJoint:
                        continue
                    if not self._pair_collides(ref_data, a, b):
                        pairs.append((b, a))
        for a in robot_ids + tool_ids:
            if geom.geometryObjects[a].parentJoint == 0:
                continue
            for b in box_ids:
                pairs.append((a, b))
        for a, b in pairs:
            geom.addCollisionPair(pin.CollisionPair(a, b))
        self.collision_pairs = [(geom.geometryObjects[a].name, geom.geometryObjects[b].name)
                                for a, b in pairs]
        self._sweep_radius = self._joint_sweep_radii()
        self._local = threading.local()

    def __repr__(self) -> str:
        return (f"CollisionChecker({self.arm.name!r}, boxes={len(self.scene.boxes)}, "
                f"meshes={len(self.scene.meshes)}, tool parts={len(self.tool_geometry_names)}, "
                f"pairs={len(self.collision_pairs)}, capsules={self.uses_capsules})")

    # -- construction helpers

    def _urdf_geometry(self) -> Any:
        import pinocchio as pin

        arm = self.arm
        confined_meshes(arm.urdf_path, arm.package_dirs)
        try:
            full = pin.buildModelFromUrdf(str(arm.urdf_path))
            geom = pin.buildGeomFromUrdf(full, str(arm.urdf_path), pin.GeometryType.COLLISION,
                                         package_dirs=arm.package_dirs)
        except (RuntimeError, ValueError) as exc:
            raise InputDataError(f"cannot load the collision geometry of {arm.urdf_path}: "
                                 f"{exc}") from None
        if arm.locked_joints:
            q_ref = pin.neutral(full)
            ids = []
            for name, value in arm.locked_joints.items():
                jid = full.getJointId(name)
                q_ref[full.idx_qs[jid]] = value
                ids.append(jid)
            _, geom = pin.buildReducedModel(full, geom, ids, q_ref)
        for obj in geom.geometryObjects:
            # joint ids must match the arm's model (same URDF, same locked joints)
            if arm.model.names[obj.parentJoint] != self._joint_name(full, obj.parentJoint,
                                                                     arm.locked_joints):
                raise InputDataError(f"collision geometry of {arm.urdf_path} does not match "
                                     "the arm's joints")
        return geom

    @staticmethod
    def _joint_name(full: Any, reduced_id: int, locked: dict[str, float]) -> str:
        names = [n for n in list(full.names) if n not in locked]
        return names[reduced_id]

    def _tool_objects(self) -> list[Any]:
        """The scene's tool parts as geometry objects on the joint that carries its frame."""
        import pinocchio as pin

        tool = self.scene.tool
        if tool is None:
            return []
        model = self.arm.model
        if not model.existFrame(tool.frame):
            raise InputDataError(f"the scene's tool frame {tool.frame!r} is not a frame of "
                                 f"{self.arm.name}")
        frame = model.frames[model.getFrameId(tool.frame)]
        if frame.parentJoint == 0:
            raise InputDataError(f"the scene's tool frame {tool.frame!r} is fixed to the base "
                                 f"of {self.arm.name}; mount the tool on a frame the arm moves")
        out = []
        for box in tool.boxes:
            out.append(pin.GeometryObject(f"tool:{box.name}", int(frame.parentJoint), 0,
                                          frame.placement * pin.SE3(box.rotation, box.center),
                                          _coal_box(2.0 * box.half_extents)))
        for mesh in tool.meshes:
            out.append(pin.GeometryObject(f"tool:{mesh.name}", int(frame.parentJoint), 0,
                                          frame.placement * pin.SE3(mesh.rotation,
                                                                    mesh.position),
                                          mesh.geometry))
        return out

    def _link_of(self, geometry_id: int) -> str:
        """The URDF link a robot geometry belongs to (its name without pinocchio's suffix)."""
        name = self.geometry_model.geometryObjects[geometry_id].name
        return name.rsplit("_", 1)[0] if name.rsplit("_", 1)[-1].isdigit() else name

    def _srdf_disabled(self) -> set[frozenset[str]]:
        """Link pairs the robot's SRDF disables (``srdf/<stem>.srdf`` beside the URDF's
        folder, as example-robot-data lays them out); empty without one."""
        import xml.etree.ElementTree as ET

        urdf = self.arm.urdf_path
        stems = dict.fromkeys([urdf.stem, urdf.stem.removesuffix("_robot")])
        candidates = [urdf.parent.parent / "srdf" / f"{stem}.srdf" for stem in stems] + [
            urdf.with_suffix(".srdf")]
        path = next((c for c in candidates if c.is_file()), None)
        if path is None or self.uses_capsules:
            return set()
        try:
            root = ET.parse(str(path)).getroot()
        except (OSError, ET.ParseError) as exc:
            raise InputDataError(f"cannot read the SRDF {path}: {exc}") from None
        return {frozenset((d.get("link1", ""), d.get("link2", "")))
                for d in root.iter("disable_collisions")}

    def _capsule_geometry(self, link_radius: float, tool_radius: float,
                          tool_capsule: bool = True) -> Any:
        import coal
        import pinocchio as pin

        model = self.arm.model
        geom = pin.GeometryModel()
        children: dict[int, list[int]] = {}
        for j in range(1, model.njoints):
            children.setdefault(int(model.parents[j]), []).append(j)
        for j in range(0, model.njoints):
            origin = np.zeros(3)
            ends = [np.array(model.jointPlacements[c].translation) for c in children.get(j, [])]
            for k, end in enumerate(ends):
                if np.linalg.norm(end) < 1e-9:
                    continue
                placement, half = _capsule_placement(origin, end)
                geom.addGeometryObject(pin.GeometryObject(
                    f"{model.names[j]}_capsule{k}", j, 0, placement,
                    coal.Capsule(link_radius, 2.0 * half)))
        tool = model.frames[self.arm.tool_frame_id]
        tip = np.array(tool.placement.translation)
        length = float(np.linalg.norm(tip))
        if tool_capsule and length > tool_radius:
            end = tip * (length - tool_radius) / length
            placement, half = _capsule_placement(np.zeros(3), end)
            geom.addGeometryObject(pin.GeometryObject(
                "tool_capsule", int(tool.parentJoint), 0, placement,
                coal.Capsule(tool_radius, 2.0 * half)))
        return geom

    def _pair_collides(self, data: Any, a: int, b: int) -> bool:
        import coal

        ga = self.geometry_model.geometryObjects[a]
        gb = self.geometry_model.geometryObjects[b]
        ta = data.oMi[ga.parentJoint] * ga.placement
        tb = data.oMi[gb.parentJoint] * gb.placement
        request = coal.CollisionRequest()
        result = coal.CollisionResult()
        return coal.collide(ga.geometry, _coal_transform(ta), gb.geometry, _coal_transform(tb),
                            request, result) > 0

    def _joint_sweep_radii(self) -> np.ndarray:
        """R_j per joint (see module doc): a bound on point speed per unit joint speed."""
        model = self.arm.model
        rho = np.zeros(model.njoints)  # bounding-sphere radius about each joint origin
        for obj in self.geometry_model.geometryObjects:
            j = obj.parentJoint
            if obj.parentJoint == 0:
                continue
            g = obj.geometry
            g.computeLocalAABB()
            center = obj.placement.act(np.array(g.aabb_center))
            rho[j] = max(rho[j], float(np.linalg.norm(center)) + float(g.aabb_radius))
        reach = np.zeros(model.njoints)
        for j in range(model.njoints - 1, 0, -1):
            reach[j] = max(reach[j], rho[j])
            parent = model.parents[j]
            if parent > 0:
                offset = float(np.linalg.norm(model.jointPlacements[j].translation))
                reach[parent] = max(reach[parent], offset + reach[j])
        radii = np.where(self.arm.revolute, reach[1:], 1.0)
        return radii

    # -- queries

    def _state(self) -> tuple[Any, Any]:
        state = getattr(self._local, "state", None)
        if state is None:
            data = self.arm.model.createData()
            gdata = self.geometry_model.createData()
            for request in gdata.collisionRequests:
                request.security_margin = self.margin
            state = (data, gdata)
            self._local.state = state
        return state

    def in_collision(self, q: Any) -> bool:
        """Whether the arm at q touches a box or itself (any checked pair)."""
        import pinocchio as pin

        q = self.arm.check_q(q)
        data, gdata = self._state()
        return bool(pin.computeCollisions(self.arm.model, data, self.geometry_model, gdata, q,
                                          True))

    def collides_fast(self, q: np.ndarray) -> bool:
        """:meth:`in_collision` without checking q (a float64 (nq,) array within the
        limits: the planner's validity callback, called thousands of times a plan)."""
        import pinocchio as pin

        data, gdata = self._state()
        return bool(pin.computeCollisions(self.arm.model, data, self.geometry_model, gdata, q,
                                          True))

    def colliding_pairs(self, q: Any) -> list[tuple[str, str]]:
        """Names of every checked pair in collision at q."""
        import pinocchio as pin

        q = self.arm.check_q(q)
        data, gdata = self._state()
        pin.computeCollisions(self.arm.model, data, self.geometry_model, gdata, q, False)
        out = []
        for k, pair in enumerate(self.geometry_model.collisionPairs):
            if gdata.collisionResults[k].isCollision():
                out.append((self.geometry_model.geometryObjects[pair.first].name,
                            self.geometry_model.geometryObjects[pair.second].name))
        return out

    @property
    def sweep_radii(self) -> np.ndarray:
        """(nq,) R_j: no robot point moves faster than sum_j R_j |dq_j| (read-only copy)."""
        return self._sweep_radius.copy()

    def leg_samples(self, q0: Any, q1: Any, clearance: float) -> np.ndarray:
        """The (n + 1, nq) configurations :meth:`leg_in_collision` checks, q0 first, q1 last."""
        require_in_range("leg_samples", "clearance", clearance, 1e-6, 10.0)
        a = self.arm.check_q(q0)
        b = self.arm.check_q(q1)
        travel = float(self._sweep_radius @ np.abs(b - a))
        n = max(1, math.ceil(travel / clearance))
        t = np.linspace(0.0, 1.0, n + 1)[:, None]
        return a + t * (b - a)

    def leg_in_collision(self, q0: Any, q1: Any, clearance: float) -> bool:
        """Whether the straight joint-space leg q0 -> q1 hits something (see module doc).

        ``clearance`` (m): the largest distance any robot point moves between two
        checked configurations.
        """
        samples = self.leg_samples(q0, q1, clearance)
        # ends first: a blocked start or goal is the common case
        order = [0, len(samples) - 1] + list(range(1, len(samples) - 1))
        return any(self.in_collision(samples[i]) for i in order)


def confined_meshes(urdf: Path, package_dirs: list[str]) -> list[Path]:
    """The mesh files a URDF names, each checked to lie inside the robot's folders.

    ``package://pkg/file`` must resolve inside one of ``package_dirs``; a relative path
    inside the URDF's folder or a package folder; ``file://`` URIs, absolute paths and
    paths that climb out of those folders (``..``, symbolic links) are refused, so a
    robot file never makes us read a file outside the paths given.

    Raises:
        InputDataError: naming the mesh and why it is refused.
    """
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(str(urdf)).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputDataError(f"cannot read the URDF {urdf}: {exc}") from None
    folders = [Path(d).resolve() for d in [str(urdf.parent), *package_dirs]]
    found = []
    for mesh in root.iter("mesh"):
        name = mesh.get("filename", "")
        if name.startswith("package://"):
            rel = name[len("package://"):]
            candidates = [Path(d).resolve() / rel for d in package_dirs]
        elif "://" in name or Path(name).is_absolute():
            raise InputDataError(f"{urdf}: mesh {name!r} is refused: meshes are package:// "
                                 "URIs or paths relative to the robot's folder")
        else:
            candidates = [(urdf.parent / name).resolve()]
        inside = [c.resolve() for c in candidates
                  if any(c.resolve().is_relative_to(f) for f in folders)]
        if not inside:
            raise InputDataError(f"{urdf}: mesh {name!r} leaves the robot's folders "
                                 f"({', '.join(str(f) for f in folders)})")
        found.append(next((c for c in inside if c.is_file()), inside[0]))
    return found


def _coal_box(size: np.ndarray) -> Any:
    import coal

    return coal.Box(float(size[0]), float(size[1]), float(size[2]))


def _coal_transform(se3: Any) -> Any:
    import coal

    return coal.Transform3s(np.array(se3.rotation), np.array(se3.translation))
