"""What the 3-D figures draw of a cell: its meshes and boxes as triangles, the tool's parts in
the frame it is mounted on, and the detoured legs of a trajectory.

The HTML view (:mod:`subtask_opt.plotting.arm3d`) and the matplotlib figure
(:mod:`subtask_opt.plotting.serial`) draw the same geometry. A mesh may hold up to
:data:`~subtask_opt.cell.meshes.MAX_MESH_TRIANGLES` triangles, more than a page's painter or
matplotlib draws at a usable speed, so a figure draws at most ``most`` triangles of each
mesh: :func:`simplified` merges the vertices that fall in one cell of a regular grid (vertex
clustering), the cell growing until few enough triangles are left. The picture then
differs from the collision geometry by at most a cell's diagonal (stated as
``cell``); the collision checks always use the full mesh.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_int

if TYPE_CHECKING:
    from subtask_opt.cell.scene import Scene
    from subtask_opt.kinematics.serial import SerialArm

VIEW_TRIANGLES = 20_000
"""Most triangles the figures draw of all the meshes of a scene and its tool together."""


@dataclass(frozen=True, eq=False)
class Surface:
    """Triangles to draw.

    Attributes:
        name: the mesh's or box's name (text from a file: figures show it as text only).
        vertices: (V, 3) positions (m), in the base frame (a scene part) or in the tool's
            frame (a tool part).
        triangles: (T, 3) vertex indices.
        cell: the grid cell (m) the mesh was simplified with, 0 when drawn in full.
    """

    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    cell: float = 0.0


def simplified(vertices: Any, triangles: Any, most: int) -> tuple[np.ndarray, np.ndarray, float]:
    """At most ``most`` triangles resembling the mesh (vertex clustering, see module doc):
    (vertices, triangles, cell size in m, 0 when the mesh already has few enough)."""
    require_int("simplified", "most", most, 12)
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    if len(t) <= most:
        return v, t, 0.0
    lo = v.min(axis=0)
    extent = float((v.max(axis=0) - lo).max())
    cell = extent / max(2.0, np.sqrt(most))
    while True:
        keys = np.floor((v - lo) / cell).astype(np.int64)
        _, cluster = np.unique(keys, axis=0, return_inverse=True)
        cluster = cluster.reshape(-1)
        tris = cluster[t]
        keep = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
        tris = tris[keep]
        if len(tris):
            _, first = np.unique(np.sort(tris, axis=1), axis=0, return_index=True)
            tris = tris[np.sort(first)]
        if len(tris) <= most:
            break
        cell *= 1.5
    count = np.bincount(cluster).astype(np.float64)
    sums = np.stack([np.bincount(cluster, weights=v[:, k]) for k in range(3)], 1)
    centre = sums / count[:, None]
    used, tris = np.unique(tris, return_inverse=True)
    return centre[used], tris.reshape(-1, 3), float(cell)


def _box_surface(box: Any) -> Surface:
    from subtask_opt.cell.meshes import box_triangles

    corners, tris = box_triangles(box.half_extents)
    return Surface(box.name, corners @ box.rotation.T + box.center, tris)


def _mesh_surfaces(meshes: Any, most: int) -> list[Surface]:
    out = []
    for mesh in meshes:
        v, t, cell = simplified(mesh.placed_vertices(), mesh.triangles, most)
        out.append(Surface(mesh.name, v, t, cell))
    return out


def scene_surfaces(scene: Scene | None, most: int = VIEW_TRIANGLES) -> list[Surface]:
    """The scene's meshes in the base frame, each simplified to its share of ``most``
    triangles (the tool's meshes count in the share)."""
    if scene is None:
        return []
    share = _share(scene, most)
    return _mesh_surfaces(scene.meshes, share)


def tool_surfaces(scene: Scene | None, most: int = VIEW_TRIANGLES) -> list[Surface]:
    """The scene tool's boxes and meshes in the frame it is mounted on ([] without one)."""
    if scene is None or scene.tool is None:
        return []
    tool = scene.tool
    return [_box_surface(b) for b in tool.boxes] + _mesh_surfaces(tool.meshes,
                                                                  _share(scene, most))


def _share(scene: Scene, most: int) -> int:
    count = len(scene.meshes) + (len(scene.tool.meshes) if scene.tool is not None else 0)
    return max(12, most // max(count, 1))


def frame_poses(arm: SerialArm, q: np.ndarray, frame: str) -> np.ndarray:
    """(T, 4, 4) placements of the arm's frame ``frame`` at the joint rows q (Pinocchio FK).

    Raises:
        ParameterError: the arm has no such frame.
    """
    import pinocchio as pin

    model, data = arm.model, arm.data
    if not model.existFrame(frame):
        raise ParameterError(f"frame_poses: {arm.name} has no frame {frame!r}")
    fid = int(model.getFrameId(frame))
    out = np.empty((len(q), 4, 4))
    for k, row in enumerate(np.asarray(q, dtype=np.float64)):
        pin.framesForwardKinematics(model, data, row)
        out[k] = data.oMf[fid].homogeneous
    return out


@dataclass(frozen=True, eq=False)
class DetourLeg:
    """A detoured leg of a trajectory: leg ``index`` (0: from the home) runs from ``start``
    to ``end`` (s) straight in joint space through the corners ``waypoints`` ((k, n), its
    ends first and last), stopping at each (:mod:`subtask_opt.cell.detour`)."""

    index: int
    start: float
    end: float
    waypoints: np.ndarray

    def joint_path(self, per_segment: int = 24) -> np.ndarray:
        """((k - 1) * per_segment + 1, n) joint rows along the leg's straight segments."""
        require_int("DetourLeg.joint_path", "per_segment", per_segment, 1, 10_000)
        s = np.linspace(0.0, 1.0, per_segment + 1)[:-1, None]
        w = self.waypoints
        rows = [a + s * (b - a) for a, b in zip(w[:-1], w[1:], strict=True)]
        return np.vstack([*rows, w[-1:]])


def detour_legs(trajectory: Any) -> list[DetourLeg]:
    """The legs of a :class:`~subtask_opt.arm.trajectory.Trajectory` planned around an
    obstacle (kind ``"detour"``), in order."""
    legs = getattr(trajectory, "legs", None)
    if legs is None:
        raise ParameterError(f"detour_legs: a Trajectory is needed, got "
                             f"{type(trajectory).__name__}")
    return [DetourLeg(k, float(leg.start), float(leg.start + leg.duration),
                      np.asarray(leg.waypoints, dtype=np.float64))
            for k, leg in enumerate(legs) if leg.kind == "detour"]


def checked_detours(owner: str, detours: Any, nq: int) -> list[DetourLeg]:
    """``detours`` (None or DetourLeg objects) validated against an arm of ``nq`` joints."""
    if detours is None:
        return []
    out = list(detours)
    for k, leg in enumerate(out):
        if not isinstance(leg, DetourLeg):
            raise ParameterError(f"{owner}: detours[{k}] must be a DetourLeg "
                                 f"(see detour_legs), got {type(leg).__name__}")
        w = leg.waypoints
        if w.ndim != 2 or w.shape[1] != nq or len(w) < 2 or not np.all(np.isfinite(w)):
            raise ParameterError(f"{owner}: detours[{k}].waypoints must be finite with shape "
                                 f"(k >= 2, {nq}), got {w.shape}")
        if not (np.isfinite(leg.start) and np.isfinite(leg.end) and leg.end >= leg.start):
            raise ParameterError(f"{owner}: detours[{k}] must end after it starts, got "
                                 f"[{leg.start}, {leg.end}]")
    return out


__all__ = ["VIEW_TRIANGLES", "DetourLeg", "Surface", "checked_detours", "detour_legs",
           "frame_poses", "scene_surfaces", "simplified", "tool_surfaces"]
