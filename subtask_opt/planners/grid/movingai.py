"""MovingAI grid benchmark: scenario files and the octile distance-transform bench.

A scenario file (``version 1``) holds one query per line: bucket, map path,
map width, height, start x, start y, goal x, goal y, optimal length (octile
moves, diagonal sqrt(2), no corner cutting). :func:`bench` answers every row
with the goal-rooted octile distance transform and compares with the optimum.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base import files
from subtask_opt.base.errors import InputDataError, require_int
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid.distance_transform import _weights
from subtask_opt.planners.grid.world import MAX_FILE_BYTES, MAX_SIDE, GridWorld

#: |ours - optimal| above this is a mismatch (scenario files print 5 decimals).
MISMATCH_TOL = 1e-3


@dataclass(frozen=True)
class Scenarios:
    """The rows of a scenario file, column-wise.

    Attributes:
        bucket, width, height: int arrays (n,).
        start, goal: int arrays (n, 2) of cells (x, y).
        optimal: float array (n,) of optimal octile lengths.
        map_name: the map path named in the file (its first row).
    """

    bucket: np.ndarray
    width: np.ndarray
    height: np.ndarray
    start: np.ndarray
    goal: np.ndarray
    optimal: np.ndarray
    map_name: str

    def __len__(self) -> int:
        return int(self.optimal.shape[0])


def read_scenarios(path: str | Path) -> Scenarios:
    """Read a MovingAI ``.scen`` file (version 1).

    Raises:
        InputDataError: unreadable or oversize file (over
            :data:`~.world.MAX_FILE_BYTES`), missing version line, or a
            malformed row (naming the line): wrong column count, a non-number,
            a size over :data:`~.world.MAX_SIDE`, a cell outside its map size,
            a negative or non-finite optimum.
    """
    path = Path(path)
    text = files.read_text(path, "scenario file", max_bytes=MAX_FILE_BYTES)
    lines = text.splitlines()
    if not lines or lines[0].split()[:1] != ["version"]:
        first = lines[0][:40] if lines else ""
        raise InputDataError(f"{path}: first line must be 'version 1', got {first!r}")
    ints: list[tuple[int, ...]] = []
    opt: list[float] = []
    map_name = ""
    for n, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        parts = line.split("\t") if "\t" in line else line.split()
        if len(parts) != 9:
            raise InputDataError(f"{path}: line {n}: expected 9 columns, got {len(parts)}")
        try:
            if not all(p.isascii() for p in parts):  # int() reads Arabic-Indic digits too
                raise ValueError
            row = tuple(int(p) for p in (parts[0], *parts[2:8]))
            value = float(parts[8])
        except ValueError:
            raise InputDataError(f"{path}: line {n}: not a number in {line[:80]!r}") from None
        bucket, width, height, sx, sy, gx, gy = row
        if not 0 <= bucket < 2**31:
            raise InputDataError(f"{path}: line {n}: bucket must be in [0, 2**31), got {bucket}")
        if not (1 <= width <= MAX_SIDE and 1 <= height <= MAX_SIDE):
            raise InputDataError(f"{path}: line {n}: map size {width}x{height} is not within "
                                 f"1..{MAX_SIDE} cells a side")
        if not (0 <= sx < width and 0 <= gx < width and 0 <= sy < height and 0 <= gy < height):
            raise InputDataError(f"{path}: line {n}: start ({sx}, {sy}) or goal ({gx}, {gy}) "
                                 f"is outside the {width}x{height} map")
        if not np.isfinite(value) or value < 0:
            raise InputDataError(f"{path}: line {n}: optimal length must be >= 0, got {value!r}")
        map_name = map_name or parts[1]
        ints.append(row)
        opt.append(value)
    if not ints:
        raise InputDataError(f"{path}: no scenario rows")
    a = np.array(ints, dtype=np.int64)
    return Scenarios(a[:, 0], a[:, 1], a[:, 2], a[:, 3:5].copy(), a[:, 5:7].copy(),
                     np.array(opt), map_name)


@dataclass(frozen=True)
class BenchReport:
    """Outcome of :func:`bench`: per-row values and the summary figures."""

    map: str
    rows: int
    mismatches: int
    max_abs_error: float
    seconds: float
    fields: int
    focused: bool
    ours: np.ndarray
    optimal: np.ndarray

    def to_dict(self, *, per_row: bool = False) -> dict[str, Any]:
        out: dict[str, Any] = {
            "map": self.map, "rows": self.rows, "mismatches": self.mismatches,
            "max_abs_error": self.max_abs_error, "seconds": self.seconds,
            "fields": self.fields, "metric": "octile",
            "method": "focused" if self.focused else "field",
        }
        if per_row:
            out["ours"] = self.ours.tolist()
            out["optimal"] = self.optimal.tolist()
        return out

    def summary(self) -> str:
        return (f"{self.map}: {self.rows} rows, {self.mismatches} mismatches, "
                f"max |error| {self.max_abs_error:.2e}, "
                f"{'focused' if self.focused else str(self.fields) + ' goal fields'}, "
                f"{self.seconds:.2f} s")


def bench(world: GridWorld, scenarios: Scenarios, *, focused: bool = False,
          landmarks: int = 8, on_field: Callable[[int], None] | None = None) -> BenchReport:
    """Answer every scenario row with the octile distance transform.

    Rows sharing a goal share one goal-rooted transform, which stops once all
    their starts are final (exact for those cells, see
    :func:`distance_field`). With ``focused`` the transform of each row is
    ordered by value plus a lower bound of the distance left to its start
    (A* with the octile distance and ``landmarks`` ALT landmark bounds; the
    landmark fields are computed once, inside the timed part): the same exact
    values, found without sweeping the far side of the map.
    ``on_field(n_rows_done)`` is called now and then (progress bars).

    Raises:
        InputDataError: the scenario's map size differs from ``world``.
        UnreachableError: a start or goal outside the grid or blocked.
    """
    require_int("bench", "landmarks", landmarks, 0)
    if np.any(scenarios.width != world.width) or np.any(scenarios.height != world.height):
        raise InputDataError(
            f"scenarios are for a {scenarios.width[0]}x{scenarios.height[0]} map "
            f"({scenarios.map_name}), the map is {world.width}x{world.height}")
    for i in range(len(scenarios)):
        world.check_cell(f"scenario row {i + 1} start", scenarios.start[i])
        world.check_cell(f"scenario row {i + 1} goal", scenarios.goal[i])
    blocked = world.occupancy.view(np.uint8)
    side, diag, _ = _weights("octile")
    w = world.width
    goal_idx = scenarios.goal[:, 1] * w + scenarios.goal[:, 0]
    start_idx = scenarios.start[:, 1] * w + scenarios.start[:, 0]
    order = np.argsort(goal_idx, kind="stable")
    fields = int(np.unique(goal_idx).size)
    # warm-up on the shortest row, so the JIT compile stays out of the time
    short = int(np.argmin(scenarios.optimal))
    no_marks = np.zeros((0, (world.height + 2) * (world.width + 2)))
    K.octile_queries(blocked, goal_idx[short:short + 1], start_idx[short:short + 1], side, diag,
                     focused, no_marks)
    K.landmark_fields(GridWorld(np.zeros((1, 1), bool)).occupancy.view(np.uint8), side, diag, 1)
    t0 = time.perf_counter()
    marks = K.landmark_fields(blocked, side, diag, landmarks) if focused else no_marks
    ours = np.empty(len(scenarios))
    # chunks of whole goal groups, so a progress bar can advance between kernel calls
    chunk = max(1, len(order) // 50)
    i = 0
    while i < len(order):
        j = min(i + chunk, len(order))
        while j < len(order) and goal_idx[order[j]] == goal_idx[order[j - 1]]:
            j += 1
        rows = order[i:j]
        ours[rows] = K.octile_queries(blocked, goal_idx[rows], start_idx[rows], side, diag,
                                        focused, marks)
        i = j
        if on_field is not None:
            on_field(i)
    seconds = time.perf_counter() - t0
    err = np.abs(ours - scenarios.optimal)
    err = np.where(np.isfinite(err), err, np.inf)
    return BenchReport(
        map=world.name or scenarios.map_name, rows=len(scenarios),
        mismatches=int(np.count_nonzero(err > MISMATCH_TOL)),
        max_abs_error=float(err.max()), seconds=seconds, fields=fields, focused=focused,
        ours=ours, optimal=scenarios.optimal.copy())
