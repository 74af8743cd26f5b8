"""3-D targets of a serial arm (:class:`~subtask_opt.arm.targets.Targets` with poses): a
point with a tool axis, or a full pose.

Two kinds of target, read from CSV or JSON:

* **tool axis** ``x,y,z,dx,dy,dz``: the tool's z axis must point along
  (dx, dy, dz) (normalised) at (x, y, z); the rotation about that axis is free and
  is sampled every ``axis_step`` degrees (default 45, i.e. 8 samples at 0, 45, ...
  315 degrees). The zero angle puts the tool's x axis along the component,
  orthogonal to the axis, of the world axis (x, then y, then z on ties) least
  aligned with it.
* **full pose** ``x,y,z,qx,qy,qz,qw``: one tool pose (the quaternion is normalised).

``standoff`` (m) backs the tool off along its own z axis: the tool point goes to
``p - standoff * z`` (a drill standing 0.01 m in front of the hole it will drill
along +z).

CSV: a header row naming the columns in one of the two orders above (a UTF-8
BOM is accepted); every row has the same kind. JSON: ``{"targets": [{"position":
[x, y, z], "axis": [dx, dy, dz]} | {"position": [...], "quaternion": [qx, qy,
qz, qw]}, ...]}``. Errors name the row (CSV rows counted from 1 after the header,
JSON targets from 0).
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.arm.targets import MIN_AXIS_STEP, Targets
from subtask_opt.base.errors import InputDataError, ParameterError, require_in_range
from subtask_opt.base.files import parse_json

AXIS_COLUMNS: tuple[str, ...] = ("x", "y", "z", "dx", "dy", "dz")
POSE_COLUMNS: tuple[str, ...] = ("x", "y", "z", "qx", "qy", "qz", "qw")
MAX_FILE_BYTES = 32 * 1024 * 1024
"""Largest target file read (bytes); a bigger file is refused before parsing."""

_MIN_NORM = 1e-9


def axis_frame(axis: Any) -> np.ndarray:
    """A rotation matrix whose z column is ``axis`` (normalised); x as in the module doc."""
    z = np.asarray(axis, dtype=np.float64)
    norm = float(np.linalg.norm(z))
    if not math.isfinite(norm) or norm < _MIN_NORM:
        raise ParameterError(f"axis must be a non-zero finite 3-vector, got {axis!r}")
    z = z / norm
    ref = np.eye(3)[int(np.argmin(np.abs(z)))]
    x = ref - (ref @ z) * z
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


def axis_samples(axis_step: float) -> np.ndarray:
    """Rotation angles (rad) about the tool axis: 0, step, 2 step, ... below 360 degrees."""
    require_in_range("axis_step", "axis_step", axis_step, MIN_AXIS_STEP, 360.0)
    count = max(1, math.ceil(360.0 / axis_step - 1e-9))
    return np.radians(np.arange(count) * float(axis_step))


def axis_poses(point: Any, axis: Any, *, axis_step: float = 45.0,
               standoff: float = 0.0) -> np.ndarray:
    """(k, 4, 4) tool poses with the z axis along ``axis`` at ``point``, rotation sampled."""
    frame = axis_frame(axis)
    p = np.asarray(point, dtype=np.float64) - standoff * frame[:, 2]
    out = []
    for angle in axis_samples(axis_step):
        c, s = math.cos(angle), math.sin(angle)
        rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        pose = np.eye(4)
        pose[:3, :3] = frame @ rz
        pose[:3, 3] = p
        out.append(pose)
    return np.array(out)


def quaternion_pose(point: Any, quaternion: Any, *, standoff: float = 0.0) -> np.ndarray:
    """4x4 pose at ``point`` with rotation ``quaternion`` (qx, qy, qz, qw), backed off."""
    q = np.asarray(quaternion, dtype=np.float64)
    norm = float(np.linalg.norm(q))
    if not math.isfinite(norm) or norm < _MIN_NORM:
        raise ParameterError(f"quaternion must be non-zero and finite, got {quaternion!r}")
    x, y, z, w = q / norm
    rot = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    pose = np.eye(4)
    pose[:3, :3] = rot
    pose[:3, 3] = np.asarray(point, dtype=np.float64) - standoff * rot[:, 2]
    return pose


def _refuse_duplicates(arr: np.ndarray, labels: list[str]) -> None:
    """Two targets with the same position and direction (within 1e-12) are one target
    given twice, as the planar reader refuses two subtasks at one point."""
    if not np.all(np.isfinite(arr)):
        return  # reported row by row below
    _, first, inverse = np.unique(np.round(arr, 12), axis=0, return_index=True,
                                  return_inverse=True)
    inverse = np.asarray(inverse).reshape(-1)
    for i, group in enumerate(inverse):
        if first[group] != i:
            raise InputDataError(f"target {labels[i]} repeats target {labels[first[group]]} "
                                 "(same position and direction): give each target once")


def make_targets(rows: np.ndarray, *, axis_step: float = 45.0, standoff: float = 0.0,
                 labels: list[str] | None = None) -> Targets:
    """3-D Targets from an (n, 6) array of axis rows or an (n, 7) array of pose rows."""
    require_in_range("make_targets", "axis_step", axis_step, MIN_AXIS_STEP, 360.0)
    require_in_range("make_targets", "standoff", standoff, -1e3, 1e3)
    arr = np.asarray(rows, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] not in (6, 7):
        raise InputDataError(f"targets must be rows of 6 (x,y,z,dx,dy,dz) or 7 "
                             f"(x,y,z,qx,qy,qz,qw) numbers, got shape {arr.shape}")
    if arr.shape[0] == 0:
        raise InputDataError("no targets given")
    _refuse_duplicates(arr, labels or [f"row {i}" for i in range(arr.shape[0])])
    labels = labels or [f"row {i}" for i in range(arr.shape[0])]
    poses, axes, free = [], [], []
    for i, row in enumerate(arr):
        if not np.all(np.isfinite(row)):
            raise InputDataError(f"target {labels[i]} is not finite: {row.tolist()}")
        try:
            if arr.shape[1] == 6:
                block = axis_poses(row[:3], row[3:], axis_step=axis_step, standoff=standoff)
            else:
                block = quaternion_pose(row[:3], row[3:], standoff=standoff)[None]
        except ParameterError as exc:
            raise InputDataError(f"target {labels[i]}: {exc}") from None
        poses.append(block)
        axes.append(block[0, :3, 2])
        free.append(arr.shape[1] == 6)
    return Targets(arr[:, :3], poses=tuple(poses), axes=np.array(axes),
                   free_axis=np.array(free, dtype=bool), axis_step=float(axis_step),
                   standoff=float(standoff))


def _read_text(path: Path, max_bytes: int) -> str:
    from subtask_opt.base.files import read_text

    return read_text(path, "target file", max_bytes=max_bytes)  # regular files only


def _parse_csv(text: str, path: Path) -> tuple[np.ndarray, list[str]]:
    reader = csv.reader(io.StringIO(text))
    try:
        rows = [r for r in reader if any(cell.strip() for cell in r)]
    except csv.Error as exc:  # e.g. a field over the csv module's limit (an open quote)
        raise InputDataError(f"target file {path}, line {reader.line_num}: {exc}") from None
    if not rows:
        raise InputDataError(f"target file {path} is empty")
    header = tuple(cell.strip().lower() for cell in rows[0])
    if header not in (AXIS_COLUMNS, POSE_COLUMNS):
        raise InputDataError(f"target file {path}: header must be {','.join(AXIS_COLUMNS)} "
                             f"or {','.join(POSE_COLUMNS)}, got {','.join(header)}")
    values, labels = [], []
    for number, row in enumerate(rows[1:], start=1):
        label = f"row {number} of {path.name}"
        if len(row) != len(header):
            raise InputDataError(f"{label} has {len(row)} columns, expected {len(header)} "
                                 f"({','.join(header)})")
        try:  # ASCII only: float() reads Arabic-Indic and full-width digits too
            nums = [float(cell) if cell.isascii() and len(cell) <= 64 else float("x")
                    for cell in row]
        except ValueError:
            raise InputDataError(f"{label} is not all numbers: {row}") from None
        if not all(math.isfinite(v) for v in nums):
            raise InputDataError(f"{label} holds NaN or infinity: {row}")
        values.append(nums)
        labels.append(label)
    if not values:
        raise InputDataError(f"target file {path} has a header but no targets")
    return np.array(values), labels


def _parse_json(text: str, path: Path) -> tuple[np.ndarray, list[str]]:
    # depth-, number- and surrogate-checked: no RecursionError, no 5,000-digit number
    doc = parse_json(text, f"target file {path}")
    targets = doc.get("targets") if isinstance(doc, dict) else None
    if not isinstance(targets, list) or not targets:
        raise InputDataError(f"target file {path} must hold {{\"targets\": [...]}} with at "
                             "least one target")
    values, labels, kind = [], [], None
    for i, item in enumerate(targets):
        label = f"target {i} of {path.name}"
        if not isinstance(item, dict) or "position" not in item or (
                ("axis" in item) == ("quaternion" in item)):
            raise InputDataError(f"{label} must be an object with 'position' and exactly one "
                                 "of 'axis' or 'quaternion'")
        this_kind = "axis" if "axis" in item else "quaternion"
        if kind is not None and this_kind != kind:
            raise InputDataError(f"{label} is a {this_kind} target but the first target is a "
                                 f"{kind} target; use one kind per file")
        kind = this_kind
        nums: list[float] = []
        for field, size in (("position", 3), (this_kind, 3 if this_kind == "axis" else 4)):
            value = item[field]
            if (not isinstance(value, list) or len(value) != size or not all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
                raise InputDataError(f"{label}: '{field}' must be {size} numbers, got {value!r}")
            if not all(math.isfinite(v) for v in value):
                raise InputDataError(f"{label}: '{field}' holds NaN or infinity: {value!r}")
            nums.extend(float(v) for v in value)
        values.append(nums)
        labels.append(label)
    return np.array(values), labels


def load_targets(path: str | Path, *, axis_step: float = 45.0, standoff: float = 0.0,
                 max_bytes: int = MAX_FILE_BYTES) -> Targets:
    """Read pose targets from a ``.csv`` or ``.json`` file (format in the module doc).

    Raises:
        InputDataError: unreadable, oversize or malformed file, naming the row.
        ParameterError: ``axis_step`` outside (0, 360] or a bad ``standoff``.
    """
    require_in_range("load_targets", "axis_step", axis_step, MIN_AXIS_STEP, 360.0)
    require_in_range("load_targets", "standoff", standoff, -1e3, 1e3)
    path = Path(path)
    text = _read_text(path, max_bytes)
    if path.suffix.lower() == ".json":
        rows, labels = _parse_json(text, path)
    else:
        rows, labels = _parse_csv(text, path)
    return make_targets(rows, axis_step=axis_step, standoff=standoff, labels=labels)
