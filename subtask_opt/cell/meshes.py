"""Triangle meshes of a scene (STL, OBJ, DAE: whatever coal's ``MeshLoader`` reads).

:class:`Mesh` is one mesh file placed in a frame (the robot's base for an obstacle, the
tool's frame for a tool's part): ``scale`` (a number or three), ``position`` and
``rotation`` (columns = the mesh's axes in that frame). The file is read once, when the
object is made, through coal (assimp), and refused with one line naming the file when it
cannot be read, holds no triangle, is degenerate or is too large:

* at most :data:`MAX_MESH_BYTES` bytes and :data:`MAX_MESH_TRIANGLES` triangles;
* after scaling, the bounding box's diagonal within [:data:`MIN_MESH_EXTENT`,
  :data:`MAX_MESH_EXTENT`] m (a mesh in millimetres read as metres is 1000x too large:
  give ``"scale": 0.001``) and the triangles' total area at least
  :data:`MIN_MESH_AREA` m^2 (not every triangle collapsed to a line or a point).

coal checks a mesh as its surface (a triangle soup), not as a solid: an arm link held
entirely inside a closed mesh, touching none of its triangles, is not in collision. Legs
are swept densely enough (:mod:`subtask_opt.cell.scene`) that no link can pass through a
surface between two checks, so only a configuration that starts inside a mesh could hide
there; the configurations of a tour start at the home, which is checked.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.base.files import check_input_file

MAX_MESH_BYTES = 32 * 1024 * 1024
"""The largest mesh file a scene accepts (32 MiB)."""
MAX_MESH_TRIANGLES = 200_000
"""Most triangles one mesh may hold (collision checks and the 3-D view stay fast)."""
MIN_MESH_EXTENT = 1e-4
"""Smallest bounding-box diagonal (m) of a mesh after scaling."""
MAX_MESH_EXTENT = 100.0
"""Largest bounding-box diagonal (m) of a mesh after scaling."""
MIN_MESH_AREA = 1e-10
"""Smallest total triangle area (m^2) of a mesh after scaling."""
ROTATION_TOL = 1e-6
"""How far a rotation's columns may be from orthonormal (and its determinant from 1)."""


def check_rotation(label: str, value: Any) -> np.ndarray:
    """A 3x3 rotation from ``value`` (nested lists), or InputDataError naming ``label``."""
    try:
        rot = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputDataError(f"{label} must be a 3x3 matrix of numbers, got {value!r}") from None
    if rot.shape != (3, 3) or not np.all(np.isfinite(rot)):
        raise InputDataError(f"{label} must be a finite 3x3 matrix, got {value!r}")
    if (np.abs(rot.T @ rot - np.eye(3)).max() > ROTATION_TOL
            or abs(np.linalg.det(rot) - 1.0) > ROTATION_TOL):
        raise InputDataError(f"{label} must be a rotation (orthonormal columns, det +1), "
                             f"got {value!r}")
    return rot


@dataclass(frozen=True, eq=False)
class Mesh:
    """One triangle mesh placed in a frame.

    Attributes:
        name: label (unique among a scene's meshes).
        file: the mesh file.
        scale: (3,) scale per axis of the file's coordinates (> 0).
        position: (3,) where the mesh's origin lies (m).
        rotation: 3x3, columns = the mesh's axes.
        geometry: the coal BVH model (scaled, in the mesh's own frame; read-only use).

    Raises:
        InputDataError: the file is missing, unreadable or refused (see module doc).
        ParameterError: a bad name, scale, position or rotation.
    """

    name: str
    file: Path
    scale: Any = 1.0
    position: Any = (0.0, 0.0, 0.0)
    rotation: Any = None
    geometry: Any = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError(f"Mesh.name must be a non-empty string, got {self.name!r}")
        scale = np.broadcast_to(np.asarray(self.scale, dtype=np.float64), (3,)).copy() if (
            np.ndim(self.scale) in (0, 1) and np.size(self.scale) in (1, 3)) else None
        if scale is None or not np.all(np.isfinite(scale)) or np.any(scale <= 0):
            raise ParameterError(f"mesh {self.name!r}: scale must be a number > 0 or three, "
                                 f"got {self.scale!r}")
        position = np.asarray(self.position, dtype=np.float64)
        if position.shape != (3,) or not np.all(np.isfinite(position)):
            raise ParameterError(f"mesh {self.name!r}: position must be 3 finite numbers, "
                                 f"got {self.position!r}")
        try:
            rotation = (np.eye(3) if self.rotation is None
                        else check_rotation(f"mesh {self.name!r}: rotation", self.rotation))
        except InputDataError as exc:
            raise ParameterError(str(exc)) from None
        for name, arr in (("scale", scale), ("position", position), ("rotation", rotation)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "file", Path(self.file))
        object.__setattr__(self, "geometry", load_mesh(self.file, scale))

    @property
    def vertices(self) -> np.ndarray:
        """(V, 3) vertices in the mesh's frame, scaled (not placed)."""
        return np.array(self.geometry.vertices(), dtype=np.float64)

    @property
    def triangles(self) -> np.ndarray:
        """(T, 3) vertex indices of every triangle."""
        return triangle_indices(self.geometry)

    def placed_vertices(self, frame: np.ndarray | None = None) -> np.ndarray:
        """(V, 3) vertices in the frame the mesh is placed in (then through the 4x4 ``frame``)."""
        points = self.vertices @ self.rotation.T + self.position
        if frame is not None:
            points = points @ frame[:3, :3].T + frame[:3, 3]
        return points


def write_stl(path: str | Path, vertices: Any, triangles: Any) -> Path:
    """Write a binary STL of (V, 3) vertices (m) and (T, 3) vertex indices; returns the path.

    Facet normals are written as the right-hand normal of each triangle's vertex order.
    """
    import struct

    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or not np.all(np.isfinite(v)):
        raise ParameterError(f"write_stl: vertices must be (V, 3) finite, got shape {v.shape}")
    if t.ndim != 2 or t.shape[1] != 3 or t.size == 0 or t.min() < 0 or t.max() >= len(v):
        raise ParameterError(f"write_stl: triangles must be (T, 3) indices into the "
                             f"{len(v)} vertices, got shape {t.shape}")
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    normal = np.cross(b - a, c - a)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    rows = np.concatenate([normal, a, b, c], axis=1).astype("<f4")
    record = np.zeros(len(t), dtype=[("f", "<f4", (12,)), ("attr", "<u2")])
    record["f"] = rows
    path = Path(path)
    with open(path, "wb") as f:
        f.write(b"subtask_opt binary STL".ljust(80, b" "))
        f.write(struct.pack("<I", len(t)))
        f.write(record.tobytes())
    return path


def box_triangles(half_extents: Any) -> tuple[np.ndarray, np.ndarray]:
    """(8, 3) vertices and (12, 3) outward triangles of a box centred at the origin."""
    h = np.asarray(half_extents, dtype=np.float64)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * h
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4),
             (1, 5, 7, 3)]
    tris = [t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))]
    return corners, np.array(tris, dtype=np.int64)


def curved_sheet(center: Any = (0.5, 0.0, 0.05), size: Any = (0.3, 0.7),
                 curvature: float = 0.6, thickness: float = 0.004,
                 divisions: tuple[int, int] = (8, 16)) -> tuple[np.ndarray, np.ndarray]:
    """A closed sheet bent about the y axis, as (V, 3) vertices and (T, 3) triangles.

    Its top is ``z = cz + curvature (x - cx)^2`` over ``|x - cx| <= size[0] / 2``,
    ``|y - cy| <= size[1] / 2``, its bottom ``thickness`` lower, the rims closed (a
    part to drill, for examples and benchmarks; :func:`write_stl` writes it).
    """
    c = np.asarray(center, dtype=np.float64)
    lx, ly = (float(v) for v in size)
    nx, ny = divisions
    if c.shape != (3,) or not np.all(np.isfinite(c)) or min(lx, ly) <= 0 or thickness <= 0:
        raise ParameterError(f"curved_sheet: center must be 3 numbers and size, thickness "
                             f"> 0, got {center!r}, {size!r}, {thickness!r}")
    if not (isinstance(nx, int) and isinstance(ny, int) and 2 <= min(nx, ny)
            and nx * ny <= 100_000):
        raise ParameterError(f"curved_sheet: divisions must be two ints >= 2 with a product "
                             f"<= 100000, got {divisions!r}")
    xs, ys = np.linspace(-lx / 2, lx / 2, nx), np.linspace(-ly / 2, ly / 2, ny)
    x, y = np.meshgrid(xs, ys, indexing="ij")
    top = np.stack([x + c[0], y + c[1], c[2] + curvature * x ** 2], -1).reshape(-1, 3)
    vertices = np.vstack([top, top - [0.0, 0.0, thickness]])
    n = len(top)

    def at(i: int, j: int) -> int:
        return i * ny + j

    tris = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            a, b, cc, d = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
            tris += [(a, b, cc), (a, cc, d), (a + n, cc + n, b + n), (a + n, d + n, cc + n)]
    rim = ([at(i, 0) for i in range(nx)] + [at(nx - 1, j) for j in range(1, ny)]
           + [at(i, ny - 1) for i in range(nx - 2, -1, -1)]
           + [at(0, j) for j in range(ny - 2, 0, -1)])
    for a, b in zip(rim, rim[1:] + rim[:1], strict=True):
        tris += [(a, a + n, b + n), (a, b + n, b)]
    return vertices, np.array(tris, dtype=np.int64)


def triangle_indices(geometry: Any) -> np.ndarray:
    """(T, 3) vertex indices of a coal BVH model's triangles."""
    out = np.empty((int(geometry.num_tris), 3), dtype=np.int64)
    for k in range(out.shape[0]):
        tri = geometry.tri_indices(k)
        out[k] = (tri[0], tri[1], tri[2])
    return out


def load_mesh(path: Path, scale: np.ndarray) -> Any:
    """The coal BVH model of a mesh file, scaled, after the checks of the module doc."""
    import coal

    check_input_file(path, "mesh file", max_bytes=MAX_MESH_BYTES)
    try:
        geometry = coal.MeshLoader().load(str(path), np.asarray(scale, dtype=np.float64))
    except (ValueError, RuntimeError) as exc:
        reason = next((line.split("message:", 1)[1].strip() for line in str(exc).splitlines()
                       if "message:" in line), "")
        detail = [line.strip() for line in str(exc).splitlines()
                  if line.strip() and ":" not in line][:1]
        why = "; ".join(x for x in [reason, *detail] if x) or "unreadable"
        raise InputDataError(f"cannot read mesh file {path}: {why}") from None
    tris = int(geometry.num_tris)
    if tris == 0:
        raise InputDataError(f"mesh file {path} holds no triangle")
    if tris > MAX_MESH_TRIANGLES:
        raise InputDataError(f"mesh file {path} has {tris} triangles, more than "
                             f"{MAX_MESH_TRIANGLES}: simplify it")
    vertices = np.array(geometry.vertices(), dtype=np.float64)
    if not np.all(np.isfinite(vertices)):
        raise InputDataError(f"mesh file {path} has vertices that are not finite")
    extent = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    if extent < MIN_MESH_EXTENT or extent > MAX_MESH_EXTENT:
        raise InputDataError(
            f"mesh file {path} is {extent:.4g} m across after scaling, outside "
            f"[{MIN_MESH_EXTENT:g}, {MAX_MESH_EXTENT:g}] m (a mesh in millimetres needs "
            "\"scale\": 0.001)")
    tri = triangle_indices(geometry)
    a, b, c = vertices[tri[:, 0]], vertices[tri[:, 1]], vertices[tri[:, 2]]
    area = 0.5 * float(np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())
    if area < MIN_MESH_AREA:
        raise InputDataError(f"mesh file {path} is degenerate: its triangles have a total "
                             f"area of {area:.3g} m^2 (at least {MIN_MESH_AREA:g})")
    geometry.computeLocalAABB()
    return geometry


__all__ = ["MAX_MESH_BYTES", "MAX_MESH_EXTENT", "MAX_MESH_TRIANGLES", "MIN_MESH_AREA",
           "MIN_MESH_EXTENT", "Mesh", "box_triangles", "check_rotation", "curved_sheet",
           "load_mesh", "triangle_indices", "write_stl"]
