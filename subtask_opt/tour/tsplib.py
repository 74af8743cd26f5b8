"""Read TSPLIB ``.tsp`` files and solve them with the sequencing solver.

:func:`read_tsplib` (a path) and :func:`parse_tsplib` (the text) return a
:class:`TspInstance` whose integer distance matrix follows the official
TSPLIB rules (Reinelt 1991, "TSPLIB 95" and its FAQ):

* ``EUC_2D``: ``nint(sqrt(dx^2 + dy^2))`` with ``nint(x) = (int)(x + 0.5)``;
* ``CEIL_2D``: the Euclidean distance rounded up;
* ``ATT``: ``r = sqrt((dx^2 + dy^2) / 10)``, ``t = nint(r)``, ``t + 1`` if ``t < r`` else ``t``;
* ``GEO``: ``DDD.MM`` degrees and minutes; ``deg = (int) x``, ``min = x - deg``,
  ``rad = PI (deg + 5 min / 3) / 180`` with ``PI = 3.141592``, and
  ``d = (int)(RRR acos(0.5 ((1 + q1) q2 - (1 - q1) q3)) + 1)`` with
  ``RRR = 6378.388``;
* ``EXPLICIT``: the weights as given, in ``FULL_MATRIX``, ``UPPER_ROW``,
  ``LOWER_ROW``, ``UPPER_DIAG_ROW``, ``LOWER_DIAG_ROW`` (and the ``*_COL``
  forms, which for a symmetric matrix hold the same numbers as a ``*_ROW``
  form).

The diagonal of the matrix is 0 (files put 0 or a large sentinel there; no
tour uses it). Anything malformed raises :class:`InputDataError` naming the
line. The dense matrix is held in memory, so ``DIMENSION`` is limited by
``max_matrix_bytes`` (default 1 GiB: at most :data:`MAX_DIMENSION` cities).

:func:`solve_tsp` runs :func:`subtask_opt.solve` on the instance and proves a
lower bound (:func:`subtask_opt.tour.bound.lower_bound`) so the answer comes
with the largest possible gap to the optimum.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError, require_int, require_positive

PI = 3.141592
"""The value of pi the TSPLIB GEO rule prescribes (not math.pi)."""
RRR = 6378.388
"""Earth radius of the TSPLIB GEO rule [km]."""

EDGE_WEIGHT_TYPES = ("EUC_2D", "CEIL_2D", "ATT", "GEO", "EXPLICIT")
EDGE_WEIGHT_FORMATS = ("FULL_MATRIX", "UPPER_ROW", "LOWER_ROW", "UPPER_DIAG_ROW",
                       "LOWER_DIAG_ROW", "UPPER_COL", "LOWER_COL", "UPPER_DIAG_COL",
                       "LOWER_DIAG_COL")
PROBLEM_TYPES = ("TSP", "ATSP")

MAX_MATRIX_BYTES = 2**30
"""Default memory budget of the dense int64 distance matrix (1 GiB)."""
MAX_DIMENSION = math.isqrt(MAX_MATRIX_BYTES // 8)
"""Most cities under :data:`MAX_MATRIX_BYTES` (11585)."""
MAX_FILE_BYTES = 2**28
"""Default size limit of a file :func:`read_tsplib` reads (256 MiB)."""
MAX_DISTANCE = 2**53
"""Largest distance kept exact (float64 integers; the solver works in float64)."""

_HEADER_KEYS = ("NAME", "TYPE", "COMMENT", "DIMENSION", "CAPACITY", "EDGE_WEIGHT_TYPE",
                "EDGE_WEIGHT_FORMAT", "EDGE_DATA_FORMAT", "NODE_COORD_TYPE",
                "DISPLAY_DATA_TYPE")
_SECTIONS = ("NODE_COORD_SECTION", "EDGE_WEIGHT_SECTION", "DISPLAY_DATA_SECTION",
             "FIXED_EDGES_SECTION", "DEPOT_SECTION", "DEMAND_SECTION", "TOUR_SECTION",
             "EDGE_DATA_SECTION")
_ROWS_PER_CHUNK = 256  # rows of the distance matrix computed at once (bounds temporaries)


@dataclass(frozen=True)
class TspInstance:
    """A TSPLIB instance.

    Attributes:
        name: the NAME entry (or the file's stem).
        dimension: number of cities N.
        edge_weight_type: one of :data:`EDGE_WEIGHT_TYPES`.
        coordinates: N x 2 node coordinates (for ``EXPLICIT``: the display
            coordinates if the file has them), or None. Read-only.
        matrix: N x N int64 distances under the TSPLIB rules, diagonal 0.
            Read-only.
        comment: the COMMENT lines, joined by newlines ("" when none).
        problem_type: ``"TSP"`` (symmetric) or ``"ATSP"``.
    """

    name: str
    dimension: int
    edge_weight_type: str
    coordinates: np.ndarray | None
    matrix: np.ndarray = field(repr=False)
    comment: str = ""
    problem_type: str = "TSP"

    def __post_init__(self) -> None:
        require_int("TspInstance", "dimension", self.dimension, 3)
        if self.edge_weight_type not in EDGE_WEIGHT_TYPES:
            raise ParameterError(
                f"TspInstance.edge_weight_type must be one of {', '.join(EDGE_WEIGHT_TYPES)}, "
                f"got {self.edge_weight_type!r}")
        if self.problem_type not in PROBLEM_TYPES:
            raise ParameterError(
                f"TspInstance.problem_type must be TSP or ATSP, got {self.problem_type!r}")
        n = self.dimension
        m = np.asarray(self.matrix)
        if m.shape != (n, n) or m.dtype != np.int64:
            raise ParameterError(
                f"TspInstance.matrix must be an int64 array of shape ({n}, {n}), "
                f"got {m.dtype} {m.shape}")
        if np.any(m < 0) or np.any(np.diag(m) != 0):
            raise ParameterError("TspInstance.matrix must be >= 0 with a zero diagonal")
        if self.problem_type == "TSP" and not np.array_equal(m, m.T):
            raise ParameterError("TspInstance.matrix of a TSP must be symmetric")
        m = np.array(m, copy=True)
        m.setflags(write=False)
        object.__setattr__(self, "matrix", m)
        if self.coordinates is not None:
            c = np.array(self.coordinates, dtype=float)
            if c.shape != (n, 2) or not np.all(np.isfinite(c)):
                raise ParameterError(
                    f"TspInstance.coordinates must be finite of shape ({n}, 2), got {c.shape}")
            c.setflags(write=False)
            object.__setattr__(self, "coordinates", c)

    @property
    def symmetric(self) -> bool:
        return self.problem_type == "TSP"

    def tour_length(self, order: np.ndarray) -> int:
        """Length of the closed tour visiting the 0-based city indices ``order``."""
        o = np.asarray(order)
        n = self.dimension
        if o.shape != (n,) or not np.array_equal(np.sort(o), np.arange(n)):
            raise ParameterError(f"order must be a permutation of 0..{n - 1}, got {order!r}")
        o = o.astype(np.int64)
        return int(self.matrix[o, np.roll(o, -1)].sum())


# --------------------------------------------------------------------------- reading


def read_tsplib(path: str | Path, *, max_matrix_bytes: int = MAX_MATRIX_BYTES,
                max_file_bytes: int = MAX_FILE_BYTES) -> TspInstance:
    """Read a TSPLIB ``.tsp`` file (see the module docstring for what is accepted).

    Raises:
        InputDataError: the file is malformed, too large or not text (the
            message names the file and the line).
        OSError: the file cannot be read.
    """
    require_int("read_tsplib", "max_file_bytes", max_file_bytes, 1)
    from subtask_opt.base.files import read_bytes

    path = Path(path)
    raw = read_bytes(path, "TSPLIB file", max_bytes=max_file_bytes)  # regular files only
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputDataError(f"{path}: not a text file ({exc.reason} at byte {exc.start})") \
            from None
    return parse_tsplib(text, source=str(path), default_name=path.stem,
                        max_matrix_bytes=max_matrix_bytes)


def parse_tsplib(text: str, *, source: str = "<text>", default_name: str = "",
                 max_matrix_bytes: int = MAX_MATRIX_BYTES) -> TspInstance:
    """Parse the text of a TSPLIB ``.tsp`` file; ``source`` names it in errors."""
    require_int("parse_tsplib", "max_matrix_bytes", max_matrix_bytes, 8)
    if not isinstance(text, str):
        raise InputDataError(f"{source}: expected the text of a TSPLIB file, got "
                             f"{type(text).__name__}")
    return _Parser(text, source, max_matrix_bytes).parse(default_name)


class _Parser:
    """One pass over the lines; errors name ``source`` and the 1-based line."""

    def __init__(self, text: str, source: str, max_matrix_bytes: int) -> None:
        self.lines = text.splitlines()
        self.source = source
        self.max_dimension = math.isqrt(max_matrix_bytes // 8)
        self.pos = 0
        self.header: dict[str, tuple[str, int]] = {}
        self.comments: list[str] = []
        self.coords: np.ndarray | None = None
        self.display: np.ndarray | None = None
        self.weights: np.ndarray | None = None
        self.weights_line = 0

    def error(self, line: int, message: str) -> InputDataError:
        where = f"{self.source} line {line}" if line > 0 else self.source
        return InputDataError(f"{where}: {message}")

    # -- driver
    def parse(self, default_name: str) -> TspInstance:
        for number, raw in enumerate(self.lines, start=1):  # Arabic-Indic digits and the
            # like would pass int() and float(); only names and comments may be Unicode
            if not raw.isascii() and not raw.lstrip().upper().startswith(("NAME", "COMMENT")):
                bad = next(c for c in raw if not c.isascii())
                raise self.error(number, f"a non-ASCII character {bad!a} outside NAME and "
                                         "COMMENT")
        while self.pos < len(self.lines):
            number = self.pos + 1
            line = self.lines[self.pos].strip()
            self.pos += 1
            if not line:
                continue
            word = line.rstrip(":").strip().upper()
            if word == "EOF":
                break
            if word in _SECTIONS:
                self.section(word, number)
                continue
            if ":" not in line:
                raise self.error(number, f"expected 'KEYWORD : value' or a section name, "
                                         f"got {_clip(line)!r}")
            key, value = (part.strip() for part in line.split(":", 1))
            key = key.upper()
            if key not in _HEADER_KEYS:
                raise self.error(number, f"unknown keyword {_clip(key)!r}")
            if key == "COMMENT":
                self.comments.append(value)
                continue
            if key in self.header:
                raise self.error(number, f"{key} given twice (first on line "
                                         f"{self.header[key][1]})")
            self.header[key] = (value, number)
            if key == "DIMENSION":
                self.dimension_value()
        return self.finish(default_name)

    def dimension_value(self) -> int:
        value, line = self.header["DIMENSION"]
        try:
            n = int(value)
        except ValueError:
            raise self.error(line, f"DIMENSION must be a whole number, got "
                                   f"{_clip(value)!r}") from None
        if n < 3:
            raise self.error(line, f"DIMENSION must be at least 3, got {n}")
        if n > self.max_dimension:
            raise self.error(line, f"DIMENSION {n} is over the limit of {self.max_dimension} "
                                   f"cities (the dense distance matrix needs {8 * n * n} "
                                   f"bytes; raise max_matrix_bytes to allow more)")
        return n

    def require_dimension(self, number: int, what: str) -> int:
        if "DIMENSION" not in self.header:
            raise self.error(number, f"{what} before DIMENSION (DIMENSION is missing)")
        return self.dimension_value()

    # -- sections
    def section(self, name: str, number: int) -> None:
        if name == "NODE_COORD_SECTION":
            if self.coords is not None:
                raise self.error(number, "NODE_COORD_SECTION given twice")
            self.coords = self.coordinates(self.require_dimension(number, name))
        elif name == "DISPLAY_DATA_SECTION":
            if self.display is not None:
                raise self.error(number, "DISPLAY_DATA_SECTION given twice")
            self.display = self.coordinates(self.require_dimension(number, name))
        elif name == "EDGE_WEIGHT_SECTION":
            if self.weights is not None:
                raise self.error(number, "EDGE_WEIGHT_SECTION given twice")
            self.weights = self.edge_weights(self.require_dimension(number, name), number)
            self.weights_line = number
        elif name == "FIXED_EDGES_SECTION":
            self.skip_until_minus_one(number, name)
        else:
            raise self.error(number, f"{name} belongs to another problem type (this reader "
                                     f"reads TSP and ATSP files)")

    def coordinates(self, n: int) -> np.ndarray:
        """``n`` lines ``index x y`` (indices 1..n, each once)."""
        out = np.full((n, 2), np.nan)
        seen = np.zeros(n, dtype=bool)
        read = 0
        while read < n:
            if self.pos >= len(self.lines):
                raise self.error(len(self.lines), f"the section ends after {read} of "
                                                  f"{n} nodes (DIMENSION {n})")
            number = self.pos + 1
            parts = self.lines[self.pos].split()
            self.pos += 1
            if not parts:
                continue
            if parts[0].rstrip(":").upper() in ("EOF", *_SECTIONS) or ":" in parts[0]:
                raise self.error(number, f"the section ends after {read} of {n} nodes "
                                         f"(DIMENSION {n})")
            if len(parts) != 3:
                raise self.error(number, f"expected 'index x y', got {len(parts)} fields")
            try:
                index = int(parts[0])
            except ValueError:
                raise self.error(number, f"node index must be a whole number, got "
                                         f"{_clip(parts[0])!r}") from None
            if not 1 <= index <= n:
                raise self.error(number, f"node index {index} is outside 1..{n}")
            if seen[index - 1]:
                raise self.error(number, f"node {index} is given twice")
            try:
                x, y = float(parts[1]), float(parts[2])
            except ValueError:
                raise self.error(number, f"coordinates must be numbers, got "
                                         f"{_clip(parts[1])!r} {_clip(parts[2])!r}") from None
            if not (math.isfinite(x) and math.isfinite(y)):
                raise self.error(number, f"coordinates must be finite, got {x} {y}")
            seen[index - 1] = True
            out[index - 1] = (x, y)
            read += 1
        self.expect_section_end(f"more than DIMENSION = {n} nodes")
        return out

    def expect_section_end(self, what: str) -> None:
        """The next non-blank line must not be more data."""
        while self.pos < len(self.lines) and not self.lines[self.pos].strip():
            self.pos += 1
        if self.pos < len(self.lines):
            first = self.lines[self.pos].split()[0]
            if _is_number(first):
                raise self.error(self.pos + 1, what)

    def edge_weights(self, n: int, start: int) -> np.ndarray:
        """Every number of the section, as whole numbers >= 0."""
        fmt, _ = self.header.get("EDGE_WEIGHT_FORMAT", ("", 0))
        fmt = fmt.upper()
        if fmt not in EDGE_WEIGHT_FORMATS:
            raise self.error(start, "EDGE_WEIGHT_SECTION needs EDGE_WEIGHT_FORMAT, one of "
                                    f"{', '.join(EDGE_WEIGHT_FORMATS)} (got {_clip(fmt)!r})")
        count = _weight_count(fmt, n)
        values = np.empty(count, dtype=np.int64)
        k = 0
        while k < count:
            if self.pos >= len(self.lines):
                raise self.error(len(self.lines), f"EDGE_WEIGHT_SECTION (line {start}) holds "
                                                  f"{k} weights; {fmt} with DIMENSION {n} "
                                                  f"needs {count}")
            number = self.pos + 1
            parts = self.lines[self.pos].split()
            self.pos += 1
            if parts and not _is_number(parts[0]):
                raise self.error(number, f"EDGE_WEIGHT_SECTION (line {start}) holds {k} "
                                         f"weights; {fmt} with DIMENSION {n} needs {count}")
            if k + len(parts) > count:
                raise self.error(number, f"more weights than {fmt} with DIMENSION {n} "
                                         f"needs ({count})")
            for token in parts:
                values[k] = self.weight(token, number)
                k += 1
        self.expect_section_end(f"more weights than {fmt} with DIMENSION {n} needs ({count})")
        return values

    def weight(self, token: str, number: int) -> int:
        try:
            value = int(token)
        except ValueError:
            value = self.whole_float(token, number)
        if not 0 <= value <= MAX_DISTANCE:
            raise self.error(number, f"edge weight must be in [0, 2**53], got {_clip(token)!r}")
        return value

    def whole_float(self, token: str, number: int) -> int:
        """A weight written like ``12.0`` or ``1e3``."""
        try:
            f = float(token)
        except ValueError:
            raise self.error(number, f"edge weight must be a number, got "
                                     f"{_clip(token)!r}") from None
        if not math.isfinite(f) or f != math.floor(f):
            raise self.error(number, f"edge weight must be a whole number, got "
                                     f"{_clip(token)!r}")
        return int(f)

    def skip_until_minus_one(self, number: int, name: str) -> None:
        while self.pos < len(self.lines):
            parts = self.lines[self.pos].split()
            self.pos += 1
            if parts and parts[0] == "-1":
                return
        raise self.error(number, f"{name} is not closed by -1")

    # -- assembling
    def finish(self, default_name: str) -> TspInstance:
        if "DIMENSION" not in self.header:
            raise self.error(0, "DIMENSION is missing")
        n = self.dimension_value()
        kind, kind_line = self.header.get("TYPE", ("TSP", 0))
        kind = kind.split()[0].upper() if kind.split() else ""
        if kind not in PROBLEM_TYPES:
            raise self.error(kind_line, f"TYPE must be TSP or ATSP, got {_clip(kind)!r}")
        if "EDGE_WEIGHT_TYPE" not in self.header:
            raise self.error(0, "EDGE_WEIGHT_TYPE is missing")
        ewt, ewt_line = self.header["EDGE_WEIGHT_TYPE"]
        ewt = ewt.upper()
        if ewt not in EDGE_WEIGHT_TYPES:
            raise self.error(ewt_line, f"EDGE_WEIGHT_TYPE must be one of "
                                       f"{', '.join(EDGE_WEIGHT_TYPES)}, got {_clip(ewt)!r}")
        coordinates = self.coords
        if ewt == "EXPLICIT":
            if self.weights is None:
                raise self.error(ewt_line, "EDGE_WEIGHT_TYPE EXPLICIT needs an "
                                           "EDGE_WEIGHT_SECTION")
            fmt = self.header["EDGE_WEIGHT_FORMAT"][0].upper()
            if kind == "ATSP" and fmt != "FULL_MATRIX":
                raise self.error(self.header["EDGE_WEIGHT_FORMAT"][1],
                                 f"an ATSP needs EDGE_WEIGHT_FORMAT FULL_MATRIX, got {fmt}")
            matrix = _explicit_matrix(self.weights, fmt, n)
            if kind == "TSP" and not np.array_equal(matrix, matrix.T):
                i, j = np.argwhere(matrix != matrix.T)[0]
                raise self.error(self.weights_line,
                                 f"TYPE TSP but the matrix is not symmetric: weight "
                                 f"{i + 1} -> {j + 1} is {matrix[i, j]}, {j + 1} -> {i + 1} "
                                 f"is {matrix[j, i]}")
            if coordinates is None:
                coordinates = self.display
        else:
            if coordinates is None:
                raise self.error(ewt_line, f"EDGE_WEIGHT_TYPE {ewt} needs a "
                                           "NODE_COORD_SECTION")
            if kind == "ATSP":
                raise self.error(kind_line, f"an ATSP needs explicit weights, not {ewt}")
            matrix = distance_matrix(coordinates, ewt)
            if matrix.max() > MAX_DISTANCE:
                raise self.error(ewt_line, "coordinates so far apart that distances exceed "
                                           "2**53")
        name = self.header.get("NAME", (default_name, 0))[0] or default_name or "unnamed"
        return TspInstance(name=name, dimension=n, edge_weight_type=ewt,
                           coordinates=coordinates, matrix=matrix,
                           comment="\n".join(self.comments), problem_type=kind)


def _weight_count(fmt: str, n: int) -> int:
    if fmt == "FULL_MATRIX":
        return n * n
    if "DIAG" in fmt:
        return n * (n + 1) // 2
    return n * (n - 1) // 2


def _explicit_matrix(values: np.ndarray, fmt: str, n: int) -> np.ndarray:
    """The N x N matrix of the weights in ``fmt`` (diagonal set to 0)."""
    if fmt == "FULL_MATRIX":
        m = values.reshape(n, n).copy()
        np.fill_diagonal(m, 0)
        return m
    # the *_COL forms list the transpose's triangle row by row
    row_form = {"UPPER_COL": "LOWER_ROW", "LOWER_COL": "UPPER_ROW",
                "UPPER_DIAG_COL": "LOWER_DIAG_ROW", "LOWER_DIAG_COL": "UPPER_DIAG_ROW"}
    fmt = row_form.get(fmt, fmt)
    m = np.zeros((n, n), dtype=np.int64)
    if fmt == "UPPER_ROW":
        i, j = np.triu_indices(n, 1)
    elif fmt == "UPPER_DIAG_ROW":
        i, j = np.triu_indices(n, 0)
    elif fmt == "LOWER_ROW":
        i, j = np.tril_indices(n, -1)
    else:  # LOWER_DIAG_ROW
        i, j = np.tril_indices(n, 0)
    m[i, j] = values
    m[j, i] = values
    np.fill_diagonal(m, 0)
    return m


def distance_matrix(coordinates: np.ndarray, edge_weight_type: str) -> np.ndarray:
    """TSPLIB integer distances between N x 2 ``coordinates`` (diagonal 0).

    ``edge_weight_type`` is ``EUC_2D``, ``CEIL_2D``, ``ATT`` or ``GEO``.
    """
    c = np.asarray(coordinates, dtype=float)
    if c.ndim != 2 or c.shape[1] != 2:
        raise ParameterError(f"coordinates must be N x 2, got shape {c.shape}")
    kinds = ("EUC_2D", "CEIL_2D", "ATT", "GEO")
    if edge_weight_type not in kinds:
        raise ParameterError(
            f"edge_weight_type must be one of {', '.join(kinds)}, got {edge_weight_type!r}")
    n = c.shape[0]
    out = np.empty((n, n), dtype=np.int64)
    if edge_weight_type == "GEO":
        deg = np.trunc(c)  # (int) x: truncation toward zero (TSPLIB FAQ)
        rad = PI * (deg + 5.0 * (c - deg) / 3.0) / 180.0
        lat, lon = rad[:, 0], rad[:, 1]
    for lo in range(0, n, _ROWS_PER_CHUNK):
        hi = min(lo + _ROWS_PER_CHUNK, n)
        if edge_weight_type == "GEO":
            q1 = np.cos(lon[lo:hi, None] - lon[None, :])
            q2 = np.cos(lat[lo:hi, None] - lat[None, :])
            q3 = np.cos(lat[lo:hi, None] + lat[None, :])
            arg = np.clip(0.5 * ((1.0 + q1) * q2 - (1.0 - q1) * q3), -1.0, 1.0)
            d = np.floor(RRR * np.arccos(arg) + 1.0)
        else:
            dx = c[lo:hi, None, 0] - c[None, :, 0]
            dy = c[lo:hi, None, 1] - c[None, :, 1]
            with np.errstate(over="ignore", invalid="ignore"):  # caught just below
                squared = dx * dx + dy * dy
            if edge_weight_type == "EUC_2D":
                d = np.floor(np.sqrt(squared) + 0.5)
            elif edge_weight_type == "CEIL_2D":
                d = np.ceil(np.sqrt(squared))
            else:  # ATT
                r = np.sqrt(squared / 10.0)
                t = np.floor(r + 0.5)
                d = np.where(t < r, t + 1.0, t)
        if not np.all(np.isfinite(d)) or d.max(initial=0.0) > MAX_DISTANCE:
            raise InputDataError("coordinates so far apart that distances exceed 2**53")
        out[lo:hi] = d.astype(np.int64)
    np.fill_diagonal(out, 0)
    return out


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _clip(text: str, limit: int = 40) -> str:
    return text if len(text) <= limit else text[:limit] + "..."


# --------------------------------------------------------------------------- solving

BOUND_SHARE = 0.25
"""Least share of :func:`solve_tsp`'s time limit the lower bound may use."""


@dataclass(frozen=True)
class TspSolution:
    """A tour of a :class:`TspInstance` and how far from the optimum it may be.

    Attributes:
        name: the instance's name.
        order: 0-based city indices of the closed tour (TSPLIB node ids are
            ``order + 1``).
        length: tour length in TSPLIB units.
        lower_bound: no tour is shorter (:func:`subtask_opt.tour.bound.lower_bound`).
        gap_bound: ``(length - lower_bound) / lower_bound``: the tour is at most
            this fraction above the optimum (0 means proven optimal).
        runtime_s: wall time of the search and the bound together.
        bound_runtime_s: the part spent on the bound.
        seed: the solver seed.
        generations: micro-GA generations run.
    """

    name: str
    order: np.ndarray
    length: int
    lower_bound: float
    gap_bound: float
    runtime_s: float
    bound_runtime_s: float
    seed: int
    generations: int

    def summary(self) -> str:
        return (f"{self.name}: tour length {self.length}, lower bound {self.lower_bound:g}, "
                f"at most {100 * self.gap_bound:.2f}% above the optimum "
                f"({self.generations} generations, {self.runtime_s:.2f} s)")

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "order": [int(i) for i in self.order],
                "tour": [int(i) + 1 for i in self.order], "length": self.length,
                "lower_bound": self.lower_bound, "gap_bound": self.gap_bound,
                "runtime_s": self.runtime_s, "bound_runtime_s": self.bound_runtime_s,
                "seed": self.seed, "generations": self.generations}


def solve_tsp(instance: TspInstance, *, time_limit: float = 10.0, seed: int = 0,
              progress: bool = False, bound_iterations: int | None = None) -> TspSolution:
    """Solve ``instance`` with :func:`subtask_opt.solve` and bound its gap.

    The search stops at the solver's default stop (its ``NoImprovement``) or
    after ``time_limit`` seconds, whichever comes first; then
    :func:`~subtask_opt.tour.bound.lower_bound` runs with the tour's length as
    its upper value, for at most ``bound_iterations`` steps and for what the
    search left of ``time_limit`` but at least :data:`BOUND_SHARE` of it. So the
    whole call takes at most about ``(1 + BOUND_SHARE) * time_limit``; only the
    bound (never the tour) may then depend on the machine's speed.
    """
    from subtask_opt.base.stop import MaxRuntime
    from subtask_opt.tour.bound import DEFAULT_ITERATIONS, lower_bound
    from subtask_opt.tour.problem import MatrixProblem
    from subtask_opt.tour.solve import SolverParams, solve

    if not isinstance(instance, TspInstance):
        raise ParameterError(f"solve_tsp needs a TspInstance, got {type(instance).__name__}")
    require_positive("solve_tsp", "time_limit", time_limit)
    require_int("solve_tsp", "seed", seed, 0)
    iterations = DEFAULT_ITERATIONS if bound_iterations is None else bound_iterations
    require_int("solve_tsp", "bound_iterations", iterations, 1)
    started = time.perf_counter()
    params = SolverParams()
    problem = MatrixProblem(instance.matrix)
    result = solve(problem, seed=seed, params=params, progress=progress,
                   stop=[*params.default_stop(), MaxRuntime(float(time_limit))])
    length = instance.tour_length(result.order)
    bound_started = time.perf_counter()
    # the bound gets what the search left of the limit, and at least a quarter of it
    budget = max(time_limit - (bound_started - started), BOUND_SHARE * time_limit)
    bound = lower_bound(instance.matrix, iterations=iterations, upper=float(length), seed=seed,
                        time_limit=budget)
    done = time.perf_counter()
    gap = (length - bound) / bound if bound > 0 else (0.0 if length == 0 else math.inf)
    return TspSolution(name=instance.name, order=np.asarray(result.order, dtype=np.int64),
                       length=length, lower_bound=bound, gap_bound=max(gap, 0.0),
                       runtime_s=done - started, bound_runtime_s=done - bound_started,
                       seed=int(seed), generations=int(result.generations))
