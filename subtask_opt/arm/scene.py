"""Collision checking of a serial arm against boxes and itself (Pinocchio + coal).

A :class:`Scene` is a list of boxes read from JSON::

    {"boxes": [{"name": "panel", "center": [x, y, z], "half_extents": [a, b, c],
                "rotation": [[...], [...], [...]]}]}

(``rotation`` optional: a 3x3 matrix whose columns are the box axes in the robot's
base frame; other top-level keys such as ``"note"`` are ignored). Lengths in m.

:meth:`Scene.for_arm` binds it to a :class:`~subtask_opt.arm.serial.SerialArm`
as a :class:`CollisionChecker`. The robot's geometry is the URDF's collision
geometry (meshes resolved through the arm's package folders); a URDF with no
collision geometry gets one capsule per link instead, from each joint origin to
the next (radius ``link_radius``), and a tool capsule from the last joint to the
tool point (radius ``tool_radius``, ending one radius short so its surface just
reaches the tool point). Base-fixed geometry is checked for self-collision only
(it cannot move relative to the boxes).

Self-collision pairs: every pair of robot geometries except those on the same
joint, on a joint and its parent, and those already touching at the reference
configuration (every joint at 0, clipped into its limits), the "adjacent" and
"default" rules of MoveIt's setup assistant.

Leg checks: :meth:`CollisionChecker.leg_in_collision` tests the straight joint
line q0 -> q1 at ``n + 1`` evenly spaced configurations with
``n = ceil(sum_j R_j |q1_j - q0_j| / clearance)``, where R_j bounds the distance
from joint j's axis to any point of the geometry it carries (for a revolute
joint; 1 for a prismatic one). Between consecutive samples no point of the robot
moves more than ``clearance``, so a collision the samples miss is one no deeper
than ``clearance`` (the bound is tested).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.arm.serial import SerialArm
from subtask_opt.base.errors import InputDataError, ParameterError, require_in_range
from subtask_opt.base.files import parse_json, read_text

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


@dataclass(frozen=True)
class Scene:
    """Box obstacles around an arm. Build it with :meth:`load` or :meth:`from_dict`."""

    boxes: tuple[Box, ...] = ()

    def __post_init__(self) -> None:
        names = [b.name for b in self.boxes]
        if not all(isinstance(b, Box) for b in self.boxes):
            raise ParameterError("Scene.boxes must hold Box objects")
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ParameterError(f"Scene.boxes: names must be unique, repeated: {dup}")
        object.__setattr__(self, "boxes", tuple(self.boxes))

    @classmethod
    def from_dict(cls, doc: Any, source: str = "scene") -> Scene:
        """A scene from a parsed JSON document; InputDataError naming the bad field."""
        if not isinstance(doc, dict) or "boxes" not in doc:
            raise InputDataError(f"{source} must be a JSON object with a 'boxes' list")
        items = doc["boxes"]
        if not isinstance(items, list):
            raise InputDataError(f"{source}: 'boxes' must be a list, got {type(items).__name__}")
        boxes = []
        for i, item in enumerate(items):
            label = f"{source}: boxes[{i}]"
            if not isinstance(item, dict):
                raise InputDataError(f"{label} must be an object")
            unknown = sorted(set(item) - {"name", "center", "half_extents", "rotation"})
            if unknown:
                raise InputDataError(f"{label} has unknown field(s) {unknown}; allowed: name, "
                                     "center, half_extents, rotation")
            for field in ("center", "half_extents"):
                if field not in item:
                    raise InputDataError(f"{label} lacks the field {field!r}")
            name = item.get("name", f"box{i}")
            if not isinstance(name, str) or not name:
                raise InputDataError(f"{label}.name must be a non-empty string, got {name!r}")
            center = _vector(f"{label}.center", item["center"])
            half = _vector(f"{label}.half_extents", item["half_extents"], positive=True)
            rot = np.eye(3)
            if item.get("rotation") is not None:
                value = item["rotation"]
                try:
                    rot = np.array(value, dtype=np.float64)
                except (TypeError, ValueError):
                    raise InputDataError(f"{label}.rotation must be a 3x3 matrix of numbers, "
                                         f"got {value!r}") from None
                if rot.shape != (3, 3) or not np.all(np.isfinite(rot)):
                    raise InputDataError(f"{label}.rotation must be a finite 3x3 matrix, "
                                         f"got {value!r}")
                if (np.abs(rot.T @ rot - np.eye(3)).max() > _ROT_TOL
                        or abs(np.linalg.det(rot) - 1.0) > _ROT_TOL):
                    raise InputDataError(f"{label}.rotation must be a rotation (orthonormal "
                                         f"columns, det +1), got {value!r}")
            boxes.append(Box(name=name, center=center, half_extents=half, rotation=rot))
        try:
            return cls(boxes=tuple(boxes))
        except ParameterError as exc:
            raise InputDataError(f"{source}: {exc}") from None

    @classmethod
    def load(cls, path: str | Path) -> Scene:
        """Read a scene JSON file (UTF-8, BOM accepted, at most 8 MiB)."""
        path = Path(path)
        text = read_text(path, "scene file", max_bytes=MAX_SCENE_BYTES)  # regular files only
        doc = parse_json(text, f"scene file {path}")  # depth-limited: no RecursionError
        return cls.from_dict(doc, source=f"scene file {path.name}")

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
        geom = self._urdf_geometry()
        self.uses_capsules = geom.ngeoms == 0
        if self.uses_capsules:
            geom = self._capsule_geometry(link_radius, tool_radius)
        robot_ids = list(range(geom.ngeoms))
        box_ids = []
        for box in self.scene.boxes:
            obj = pin.GeometryObject(f"box:{box.name}", 0, 0, pin.SE3(box.rotation, box.center),
                                     _coal_box(2.0 * box.half_extents))
            box_ids.append(geom.addGeometryObject(obj))
        self.geometry_model = geom
        self.robot_geometry_names = [geom.geometryObjects[i].name for i in robot_ids]

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
        for a in robot_ids:
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

    def _capsule_geometry(self, link_radius: float, tool_radius: float) -> Any:
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
        if length > tool_radius:
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
            if obj.name.startswith("box:"):
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
