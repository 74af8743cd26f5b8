"""Planar targets: reading and writing N planar subtask positions (and optional tool
angles) as :class:`~subtask_opt.arm.targets.Targets`, in metres in the robot model's world
frame. Files: CSV with a header ``x,y`` or ``x,y,theta``, or JSON
``{"points": [[x, y], ...], "theta": [...], "name": "..."}`` (``theta`` and
``name`` optional). Built-in cases, placed inside a given arm's reachable
workspace: ``square20`` (a 5 x 4 lattice, several optimal tours) and
``random30`` (30 uniformly random reachable points, seeded).
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.arm.targets import Targets
from subtask_opt.base.errors import InputDataError, ParameterError, require_int, require_positive
from subtask_opt.base.files import parse_json, read_text
from subtask_opt.kinematics.planar import Arm

CASE_NAMES: tuple[str, ...] = ("square20", "random30")

def _number(text: str, path: Path, line: int, column: str) -> float:
    try:
        if len(text) > 64 or not text.isascii():  # float() reads Arabic-Indic digits too
            raise ValueError
        return float(text)
    except ValueError:
        raise InputDataError(
            f"{path}, line {line}: {column} is not a number: {text.strip()!r}") from None


def _load_csv(path: Path, text: str) -> Targets:
    lines = text.splitlines()
    long = next((n for n, line in enumerate(lines, start=1) if len(line) > 1000), None)
    if long is not None:
        raise InputDataError(f"{path}, line {long}: longer than 1000 characters "
                             "(expected x,y[,theta] numbers)")
    reader = csv.reader(lines)
    try:
        rows = [(n, row) for n, row in enumerate(reader, start=1)
                if row and any(cell.strip() for cell in row)]
    except csv.Error as exc:  # e.g. a field over the csv module's limit (an open quote)
        raise InputDataError(f"{path}, line {reader.line_num}: {exc}") from None
    if not rows:
        raise InputDataError(f"{path} is empty: expected a header x,y[,theta] and rows")
    line, header = rows[0]
    header = [h.strip().lower() for h in header]
    if header not in (["x", "y"], ["x", "y", "theta"]):
        raise InputDataError(
            f"{path}, line {line}: header must be x,y or x,y,theta, got {','.join(header)}")
    points, theta = [], []
    for line, row in rows[1:]:
        if len(row) != len(header):
            raise InputDataError(
                f"{path}, line {line}: expected {len(header)} values "
                f"({','.join(header)}), got {len(row)}")
        values = [_number(cell, path, line, col) for cell, col in zip(row, header, strict=True)]
        if not all(math.isfinite(v) for v in values):
            raise InputDataError(f"{path}, line {line}: values must be finite, got {values}")
        points.append(values[:2])
        if len(values) == 3:
            theta.append(values[2])
    return _build(points, theta if len(header) == 3 else None, path.stem, path)


def _load_json(path: Path, text: str) -> Targets:
    data = parse_json(text, str(path))
    if not isinstance(data, dict) or "points" not in data:
        raise InputDataError(f'{path}: expected an object {{"points": [[x, y], ...]}}')
    points = data["points"]
    if not isinstance(points, list) or not all(
            isinstance(p, list) and len(p) == 2
            and all(isinstance(v, int | float) and not isinstance(v, bool) for v in p)
            for p in points):
        raise InputDataError(f'{path}: "points" must be a list of [x, y] number pairs')
    theta = data.get("theta")
    if theta is not None and (not isinstance(theta, list) or not all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in theta)):
        raise InputDataError(f'{path}: "theta" must be a list of numbers')
    name = data.get("name") or path.stem
    if not isinstance(name, str):
        raise InputDataError(f'{path}: "name" must be a string, got {name!r}')
    return _build(points, theta, name, path)


def _build(points: Any, theta: Any, name: str, path: Path) -> Targets:
    try:
        return Targets(np.array(points, dtype=np.float64).reshape(-1, 2),
                          None if theta is None else np.array(theta, dtype=np.float64), name)
    except InputDataError as exc:
        raise InputDataError(f"{path}: {exc}") from None


def load_subtasks(path: str | Path) -> Targets:
    """Read a subtask set from ``.csv`` (header ``x,y[,theta]``) or ``.json``.

    Raises:
        InputDataError: missing file, unknown extension, or malformed content
            (the message names the line).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".json"):
        raise InputDataError(f"subtask file must end in .csv or .json, got {path.name!r}")
    text = read_text(path, "subtask file")
    return _load_csv(path, text) if suffix == ".csv" else _load_json(path, text)


def save_subtasks(subtasks: Targets, path: str | Path) -> None:
    """Write a subtask set as ``.csv`` or ``.json`` (by the extension), full precision."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".json":
        path.write_text(json.dumps(subtasks.to_dict(), indent=1) + "\n")
    elif suffix == ".csv":
        with path.open("w", newline="") as fh:
            writer = csv.writer(fh)
            if subtasks.theta is None:
                writer.writerow(["x", "y"])
                writer.writerows([repr(float(x)), repr(float(y))] for x, y in subtasks.points)
            else:
                writer.writerow(["x", "y", "theta"])
                writer.writerows([repr(float(x)), repr(float(y)), repr(float(t))]
                                 for (x, y), t in zip(subtasks.points, subtasks.theta,
                                                      strict=True))
    else:
        raise InputDataError(f"subtask file must end in .csv or .json, got {path.name!r}")


def _reachable_both(arm: Arm, pts: np.ndarray) -> tuple[bool, bool]:
    q = arm.ik(pts)
    ok = np.isfinite(q).all(axis=2)  # (M, 2 branches)
    return bool(ok.all()), bool(ok.any(axis=1).all())


def _square20(arm: Arm) -> Targets:
    """The largest 5 x 4 lattice in front of the arm (along its q = 0 direction).

    Scans spacings from large to small and distances from the base; keeps the
    lattice's hull clear of the inner disc and its points within 90% of the
    reach; takes the first lattice reachable in both elbow branches, else the
    first reachable in at least one.
    """
    a1 = arm.angle_offsets[0]
    u = np.array([math.cos(a1), math.sin(a1)])
    v = np.array([-u[1], u[0]])
    ix, iy = np.meshgrid(np.arange(5.0), np.arange(4.0))
    grid = np.column_stack([ix.ravel() - 2.0, iy.ravel() - 1.5])  # centred, rows of 5
    fallback = None
    for h in arm.r_max * np.linspace(0.2, 0.02, 91):
        for c in np.linspace(arm.r_min, arm.r_max, 101):
            pts = arm.base_xy + (c * u)[None, :] + h * (grid[:, :1] * u + grid[:, 1:] * v)
            if c - 2.0 * h <= arm.r_min:
                continue  # the lattice's hull must miss the inner disc: no leg crosses it
            if np.hypot(*(pts - arm.base_xy).T).max() > 0.9 * arm.r_max:
                continue  # and stay off the rim, where the arm is singular
            both, one = _reachable_both(arm, pts)
            if both:
                return Targets(pts, name="square20")
            if one and fallback is None:
                fallback = pts
    if fallback is None:
        raise ParameterError(f"no 5x4 lattice fits in the workspace of robot {arm.name!r}")
    return Targets(fallback, name="square20")


def random_subtasks(arm: Arm, n: int, *, seed: int = 0, min_spacing: float | None = None,
                    name: str = "") -> Targets:
    """n uniformly random points of the arm's reachable workspace, seeded.

    Rejection sampling in the bounding box of the annulus: a point is kept if
    some elbow branch reaches it within the joint limits and it lies at least
    ``min_spacing`` (default 3% of the reach) from the points already kept.
    """
    require_int("random_subtasks", "n", n, 3)
    if min_spacing is None:
        min_spacing = 0.03 * arm.r_max
    require_positive("random_subtasks", "min_spacing", min_spacing)
    rng = np.random.default_rng(seed)
    pts = np.empty((n, 2))
    count = 0
    for _ in range(200):  # batches of candidates; a bounded search, never an endless loop
        cand = arm.base_xy + rng.uniform(-arm.r_max, arm.r_max, size=(64 * n, 2))
        cand = cand[np.isfinite(arm.ik(cand)).all(axis=2).any(axis=1)]
        for p in cand:
            if count and np.hypot(*(pts[:count] - p).T).min() < min_spacing:
                continue
            pts[count] = p
            count += 1
            if count == n:
                return Targets(pts, name=name or f"random{n}")
    raise ParameterError(
        f"cannot place {n} subtasks {min_spacing:.4g} m apart in the workspace of "
        f"{arm.name!r}: lower min_spacing or n")


def builtin_case(name: str, arm: Arm, *, seed: int = 0) -> Targets:
    """A built-in subtask set inside ``arm``'s workspace: ``square20`` or ``random30``.

    ``square20`` is deterministic (``seed`` is ignored); ``random30`` draws 30
    points with :func:`random_subtasks` from ``seed``.
    """
    if name == "square20":
        return _square20(arm)
    if name == "random30":
        return random_subtasks(arm, 30, seed=seed, name="random30")
    raise ParameterError(f"unknown case {name!r}: expected one of {', '.join(CASE_NAMES)}")


__all__ = ["CASE_NAMES", "Targets", "builtin_case", "load_subtasks", "random_subtasks",
           "save_subtasks"]
