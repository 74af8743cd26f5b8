"""Read GTSPLIB and PCGLNS files: generalised TSPs, one vertex of every set visited.

:func:`read_gtsplib` (a path) and :func:`parse_gtsplib` (the text) return a
:class:`GtspInstance`; :meth:`GtspInstance.problem` is the tour core's clustered problem
(:class:`~subtask_opt.tour.problem.GtspProblem`) that :func:`subtask_opt.tour.solve.solve`
takes, and :meth:`GtspInstance.constraints` the start set and precedence of a PCGLNS file.

Accepted (TSPLIB 95 with the GTSPLIB and PCGLNS extensions):

* ``TYPE``: ``GTSP`` (symmetric), ``AGTSP`` (asymmetric) or ``PCGLNS`` (asymmetric, with
  precedence and a start set); a ``KEYWORD value`` line without the colon is read too
  (``35ftv170`` has one);
* ``EDGE_WEIGHT_TYPE``: ``EUC_2D``, ``CEIL_2D``, ``GEO``, ``ATT`` (TSPLIB's integer rules,
  :func:`subtask_opt.tour.tsplib.distance_matrix`) or ``EXPLICIT`` with
  ``EDGE_WEIGHT_FORMAT`` ``FULL_MATRIX``, ``UPPER_ROW``, ``LOWER_ROW``, ``UPPER_DIAG_ROW``
  or ``LOWER_DIAG_ROW`` (an asymmetric file needs ``FULL_MATRIX``);
* ``GTSP_SETS : m`` and ``GTSP_SET_SECTION``: ``set_id v1 v2 ... -1`` per set (ids and
  vertices 1-based; every vertex in exactly one set);
* PCGLNS: ``GTSP_SET_ORDERING`` lines ``a b c -1`` (set a before sets b and c),
  ``START_GROUP_SECTION`` (the set the tour starts in), and -1 in the matrix for a
  forbidden arc.

Anything else raises :class:`~subtask_opt.base.errors.InputDataError` naming the file, the
line and what was expected there.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError, require_int
from subtask_opt.tour.tsplib import (
    MAX_DISTANCE,
    MAX_FILE_BYTES,
    _clip,
    _is_number,
    _weight_count,
    distance_matrix,
)

PROBLEM_TYPES = ("GTSP", "AGTSP", "PCGLNS")
EDGE_WEIGHT_TYPES = ("EUC_2D", "CEIL_2D", "GEO", "ATT", "EXPLICIT")
EDGE_WEIGHT_FORMATS = ("FULL_MATRIX", "UPPER_ROW", "LOWER_ROW", "UPPER_DIAG_ROW",
                       "LOWER_DIAG_ROW")
MAX_VERTICES = 5_000
"""Most vertices a file may have (each dense (M, M) copy is 200 MB of float64 at the limit;
the problem keeps three)."""
FORBIDDEN = -1
"""The matrix entry of a forbidden arc in a PCGLNS file."""

_HEADER_KEYS = ("NAME", "TYPE", "COMMENT", "DIMENSION", "GTSP_SETS", "EDGE_WEIGHT_TYPE",
                "EDGE_WEIGHT_FORMAT", "NODE_COORD_TYPE", "DISPLAY_DATA_TYPE")
_SECTIONS = ("NODE_COORD_SECTION", "EDGE_WEIGHT_SECTION", "DISPLAY_DATA_SECTION",
             "GTSP_SET_SECTION", "GTSP_SET_ORDERING", "START_GROUP_SECTION")


@dataclass(frozen=True, eq=False)
class GtspInstance:
    """A GTSPLIB (or PCGLNS) instance, vertices and sets 0-based (the file's minus 1).

    Attributes:
        name: the NAME entry (or the file's stem).
        problem_type: ``"GTSP"``, ``"AGTSP"`` or ``"PCGLNS"``.
        edge_weight_type: one of :data:`EDGE_WEIGHT_TYPES`.
        weights: (M, M) float64 arc costs under the file's rule, zero diagonal, inf for
            a forbidden arc (read-only).
        sets: (M,) int64, the set of every vertex (read-only).
        coordinates: (M, 2) node (or display) coordinates, or None.
        precedence: (set a, set b) pairs: a is visited before b (PCGLNS).
        start: the set the tour starts in (PCGLNS), or None.
        comment: the COMMENT lines joined by newlines.
    """

    name: str
    problem_type: str
    edge_weight_type: str
    weights: np.ndarray = field(repr=False)
    sets: np.ndarray = field(repr=False)
    coordinates: np.ndarray | None = field(default=None, repr=False)
    precedence: tuple[tuple[int, int], ...] = ()
    start: int | None = None
    comment: str = ""

    @property
    def dimension(self) -> int:
        """Number of vertices M."""
        return int(self.weights.shape[0])

    @property
    def set_count(self) -> int:
        """Number of sets N."""
        return int(self.sets.max()) + 1

    def problem(self, lns_steps: int | None = None) -> Any:
        """The tour core's :class:`~subtask_opt.tour.problem.GtspProblem` (from the start
        set, if the file names one; ``lns_steps`` as there)."""
        from subtask_opt.tour.problem import GtspProblem

        return GtspProblem(self.weights, self.sets, first=self.start, lns_steps=lns_steps)

    def constraints(self) -> Any:
        """:class:`~subtask_opt.tour.constraints.TourConstraints` of the start set and the
        precedence (None for a plain GTSP)."""
        if self.start is None and not self.precedence:
            return None
        from subtask_opt.tour.constraints import TourConstraints

        return TourConstraints(start=self.start, precedence=self.precedence)

    def tour_cost(self, vertices: Any) -> float:
        """Cost of the closed tour through ``vertices`` (0-based, one of every set, in
        visiting order) from the file's weights; inf if it takes a forbidden arc."""
        v = np.asarray(vertices)
        n = self.set_count
        if (v.shape != (n,) or v.dtype.kind not in "iu" or np.any(v < 0)
                or np.any(v >= self.dimension)
                or not np.array_equal(np.sort(self.sets[v]), np.arange(n))):
            raise ParameterError(f"a tour of {self.name} must visit one vertex of each of "
                                 f"its {n} sets, got {vertices!r}")
        v = v.astype(np.int64)
        return float(self.weights[v, np.roll(v, -1)].sum())

    def violations(self, vertices: Any) -> list[str]:
        """The start and precedence rules the tour through ``vertices`` breaks (sets
        numbered as in the file); empty: it keeps them all."""
        order = self.sets[np.asarray(vertices, dtype=np.int64)]
        out = []
        if self.start is not None and order[0] != self.start:
            out.append(f"starts in set {order[0] + 1}, not {self.start + 1}")
        pos = np.empty(len(order), dtype=np.int64)
        pos[order] = np.arange(len(order))
        out += [f"set {b + 1} comes before set {a + 1}" for a, b in self.precedence
                if pos[a] > pos[b]]
        return out


def read_gtsplib(path: str | Path, *, max_file_bytes: int = MAX_FILE_BYTES) -> GtspInstance:
    """Read a GTSPLIB or PCGLNS file (see the module docstring for what is accepted).

    Raises:
        InputDataError: the file is malformed, too large or not text (the message names
            the file, the line and what was expected).
        OSError: the file cannot be read.
    """
    require_int("read_gtsplib", "max_file_bytes", max_file_bytes, 1)
    from subtask_opt.base.files import read_text

    path = Path(path)
    # a regular UTF-8 text file of at most max_file_bytes (FIFOs, devices, binary refused)
    text = read_text(path, "GTSPLIB file", max_bytes=max_file_bytes)
    return parse_gtsplib(text, source=str(path), default_name=path.stem)


def parse_gtsplib(text: str, *, source: str = "<text>", default_name: str = "") -> GtspInstance:
    """Parse the text of a GTSPLIB or PCGLNS file; ``source`` names it in errors."""
    if not isinstance(text, str):
        raise InputDataError(f"{source}: expected the text of a GTSPLIB file, got "
                             f"{type(text).__name__}")
    return _Parser(text, source).parse(default_name)


class _Parser:
    """One pass over the lines; errors name ``source`` and the 1-based line."""

    def __init__(self, text: str, source: str) -> None:
        self.lines = text.splitlines()
        self.source = source
        self.pos = 0
        self.header: dict[str, tuple[str, int]] = {}
        self.comments: list[str] = []
        self.coords: np.ndarray | None = None
        self.display: np.ndarray | None = None
        self.weights: tuple[np.ndarray, np.ndarray, int] | None = None  # values, lines, start
        self.sets: np.ndarray | None = None
        self.ordering: list[tuple[int, int, int]] = []  # (a, b, line), file numbering
        self.ordering_line = 0
        self.start: tuple[int, int] | None = None
        self.seen_sections: dict[str, int] = {}

    def error(self, line: int, message: str) -> InputDataError:
        where = f"{self.source} line {line}" if line > 0 else self.source
        return InputDataError(f"{where}: {message}")

    # -- driver
    def parse(self, default_name: str) -> GtspInstance:
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
                if word in self.seen_sections:
                    raise self.error(number, f"{word} given twice (first on line "
                                             f"{self.seen_sections[word]})")
                self.seen_sections[word] = number
                self.section(word, number)
                continue
            if ":" in line:
                key, value = (part.strip() for part in line.split(":", 1))
            else:  # "KEYWORD value" (a colon missing, as in 35ftv170)
                key, _, value = line.partition(" ")
                value = value.strip()
                if key.upper() not in _HEADER_KEYS:
                    raise self.error(number, f"expected 'KEYWORD : value' or a section "
                                             f"name, got {_clip(line)!r}")
            key = key.upper()
            if key not in _HEADER_KEYS:
                raise self.error(number, f"expected a keyword ({', '.join(_HEADER_KEYS)}) "
                                         f"or a section name, got {_clip(key)!r}")
            if key == "COMMENT":
                self.comments.append(value)
                continue
            if key in self.header:
                raise self.error(number, f"{key} given twice (first on line "
                                         f"{self.header[key][1]})")
            self.header[key] = (value, number)
            if key == "DIMENSION":
                self.dimension()
            elif key == "GTSP_SETS":
                self.set_count()
        return self.finish(default_name)

    def whole(self, key: str, low: int, high: int) -> int:
        value, line = self.header[key]
        try:
            n = int(value)
        except ValueError:
            raise self.error(line, f"expected {key} to be a whole number, got "
                                   f"{_clip(value)!r}") from None
        if not low <= n <= high:
            raise self.error(line, f"expected {key} in {low}..{high}, got {n}")
        return n

    def dimension(self) -> int:
        return self.whole("DIMENSION", 3, MAX_VERTICES)

    def set_count(self) -> int:
        return self.whole("GTSP_SETS", 3, MAX_VERTICES)

    def require(self, key: str, number: int, what: str) -> int:
        if key not in self.header:
            raise self.error(number, f"expected {key} before {what}")
        return self.dimension() if key == "DIMENSION" else self.set_count()

    def problem_type(self) -> str:
        kind, line = self.header.get("TYPE", ("", 0))
        kind = kind.split()[0].upper() if kind.split() else ""
        if kind not in PROBLEM_TYPES:
            raise self.error(line, f"expected TYPE to be one of {', '.join(PROBLEM_TYPES)}, "
                                   f"got {_clip(kind)!r}")
        return kind

    # -- sections
    def section(self, name: str, number: int) -> None:
        if name in ("NODE_COORD_SECTION", "DISPLAY_DATA_SECTION"):
            coords = self.coordinates(self.require("DIMENSION", number, name))
            if name == "NODE_COORD_SECTION":
                self.coords = coords
            else:
                self.display = coords
        elif name == "EDGE_WEIGHT_SECTION":
            self.weights = self.edge_weights(self.require("DIMENSION", number, name), number)
        elif name == "GTSP_SET_SECTION":
            self.sets = self.set_section(self.require("DIMENSION", number, name),
                                         self.require("GTSP_SETS", number, name))
        elif name == "GTSP_SET_ORDERING":
            self.ordering_line = number
            self.ordering = self.ordering_section(self.require("GTSP_SETS", number, name))
        else:
            self.start = self.start_section(self.require("GTSP_SETS", number, name), number)

    def data_lines(self) -> Any:
        """The section's non-blank lines ``(number, fields)`` up to the next keyword."""
        while self.pos < len(self.lines):
            parts = self.lines[self.pos].split()
            if parts and not _is_number(parts[0]):
                return
            self.pos += 1
            if parts:
                yield self.pos, parts

    def coordinates(self, n: int) -> np.ndarray:
        """``n`` lines ``index x y`` (indices 1..n, each once)."""
        out = np.full((n, 2), np.nan)
        read = 0
        last = self.pos
        for number, parts in self.data_lines():
            last = number
            if len(parts) != 3:
                raise self.error(number, f"expected 'index x y', got {len(parts)} fields")
            index = self.integer(parts[0], number, "a node index")
            if not 1 <= index <= n:
                raise self.error(number, f"expected a node index in 1..{n}, got {index}")
            if not np.isnan(out[index - 1, 0]):
                raise self.error(number, f"node {index} is given twice")
            try:
                x, y = float(parts[1]), float(parts[2])
            except ValueError:
                raise self.error(number, f"expected coordinates (two numbers), got "
                                         f"{_clip(parts[1])!r} {_clip(parts[2])!r}") from None
            if not (math.isfinite(x) and math.isfinite(y)):
                raise self.error(number, f"expected finite coordinates, got {x} {y}")
            out[index - 1] = (x, y)
            read += 1
        if read != n:
            raise self.error(last if read else self.pos, f"expected {n} nodes (DIMENSION "
                                                         f"{n}), the section has {read}")
        return out

    def edge_weights(self, n: int, start: int) -> tuple[np.ndarray, np.ndarray, int]:
        """Every number of the section (floats) and the line of each."""
        fmt, _ = self.header.get("EDGE_WEIGHT_FORMAT", ("", 0))
        fmt = fmt.upper()
        if fmt not in EDGE_WEIGHT_FORMATS:
            raise self.error(start, f"expected EDGE_WEIGHT_FORMAT (one of "
                                    f"{', '.join(EDGE_WEIGHT_FORMATS)}) before "
                                    f"EDGE_WEIGHT_SECTION, got {_clip(fmt)!r}")
        count = _weight_count(fmt, n)
        values = np.empty(count)
        where = np.empty(count, dtype=np.int64)
        k = 0
        last = start
        for number, parts in self.data_lines():
            last = number
            if k + len(parts) > count:
                raise self.error(number, f"expected {count} weights ({fmt}, DIMENSION {n}), "
                                         f"the section has more")
            try:
                row = np.array(parts, dtype=float)
            except ValueError:
                bad = next(p for p in parts if not _is_number(p))
                raise self.error(number, f"expected a number, got {_clip(bad)!r}") from None
            values[k:k + len(parts)] = row
            where[k:k + len(parts)] = number
            k += len(parts)
        if k < count:
            raise self.error(last, f"expected {count} weights ({fmt}, DIMENSION {n}), the "
                                   f"section has {k}")
        return values, where, start

    def integer(self, token: str, number: int, what: str) -> int:
        try:
            return int(token)
        except ValueError:
            raise self.error(number, f"expected {what} (a whole number), got "
                                     f"{_clip(token)!r}") from None

    def set_section(self, n: int, m: int) -> np.ndarray:
        """``m`` sets ``id v1 ... -1``; every vertex in exactly one."""
        sets = np.full(n, -1, dtype=np.int64)
        defined = np.zeros(m, dtype=bool)
        current = -1  # the set being read (0-based), -1 between sets
        number = self.pos
        for number, parts in self.data_lines():
            for token in parts:
                value = self.integer(token, number, "a set id or a vertex")
                if current < 0:
                    if not 1 <= value <= m:
                        raise self.error(number, f"expected a set id in 1..{m} (GTSP_SETS "
                                                 f"{m}), got {value}")
                    if defined[value - 1]:
                        raise self.error(number, f"set {value} is given twice")
                    current = value - 1
                    defined[current] = True
                    first_vertex = True
                elif value == -1:
                    if first_vertex:
                        raise self.error(number, f"expected a vertex of set {current + 1} "
                                                 f"before -1 (a set cannot be empty)")
                    current = -1
                else:
                    if not 1 <= value <= n:
                        raise self.error(number, f"expected a vertex in 1..{n} (DIMENSION "
                                                 f"{n}) or -1, got {value}")
                    if sets[value - 1] >= 0:
                        raise self.error(number, f"expected every vertex in one set, vertex "
                                                 f"{value} is in set {sets[value - 1] + 1} "
                                                 f"and set {current + 1}")
                    sets[value - 1] = current
                    first_vertex = False
        if current >= 0:
            raise self.error(number, f"expected -1 to close set {current + 1}")
        if not defined.all():
            missing = int(np.flatnonzero(~defined)[0]) + 1
            raise self.error(number, f"expected {m} sets (GTSP_SETS {m}), set {missing} is "
                                     f"missing")
        if np.any(sets < 0):
            vertex = int(np.flatnonzero(sets < 0)[0]) + 1
            raise self.error(number, f"expected every vertex in a set, vertex {vertex} is "
                                     f"in none")
        return sets

    def ordering_section(self, m: int) -> list[tuple[int, int, int]]:
        """Lines ``a b c -1``: set a before sets b and c."""
        pairs = []
        for number, parts in self.data_lines():
            ids = [self.integer(t, number, "a set id") for t in parts]
            if len(ids) < 2 or ids[-1] != -1:
                raise self.error(number, "expected 'a b ... -1' (set a before the others), "
                                         "closed by -1")
            for value in ids[:-1]:
                if not 1 <= value <= m:
                    raise self.error(number, f"expected a set id in 1..{m}, got {value}")
            pairs += [(ids[0], b, number) for b in ids[1:-1]]
        return pairs

    def start_section(self, m: int, start: int) -> tuple[int, int]:
        values = [(number, self.integer(t, number, "the start set id"))
                  for number, parts in self.data_lines() for t in parts]
        values = [(number, v) for number, v in values if v != -1]
        if len(values) != 1:
            raise self.error(values[1][0] if len(values) > 1 else start,
                             f"expected one start set id, got {len(values)}")
        number, value = values[0]
        if not 1 <= value <= m:
            raise self.error(number, f"expected a start set id in 1..{m}, got {value}")
        return value - 1, number

    # -- assembling
    def finish(self, default_name: str) -> GtspInstance:
        kind = self.problem_type()
        if "DIMENSION" not in self.header:
            raise self.error(0, "expected DIMENSION, the file has none")
        n = self.dimension()
        if self.sets is None:
            raise self.error(0, "expected a GTSP_SET_SECTION, the file has none")
        ewt, ewt_line = self.header.get("EDGE_WEIGHT_TYPE", ("", 0))
        ewt = ewt.upper()
        if ewt not in EDGE_WEIGHT_TYPES:
            raise self.error(ewt_line, f"expected EDGE_WEIGHT_TYPE to be one of "
                                       f"{', '.join(EDGE_WEIGHT_TYPES)}, got {_clip(ewt)!r}")
        coordinates = self.coords
        if ewt == "EXPLICIT":
            if self.weights is None:
                raise self.error(ewt_line, "expected an EDGE_WEIGHT_SECTION (EDGE_WEIGHT_TYPE "
                                           "EXPLICIT)")
            fmt, fmt_line = self.header["EDGE_WEIGHT_FORMAT"]
            fmt = fmt.upper()
            if kind != "GTSP" and fmt != "FULL_MATRIX":
                raise self.error(fmt_line, f"expected EDGE_WEIGHT_FORMAT FULL_MATRIX (TYPE "
                                           f"{kind} is asymmetric), got {fmt}")
            weights = self.explicit(kind, fmt, n)
            if coordinates is None:
                coordinates = self.display
        else:
            if coordinates is None:
                raise self.error(ewt_line, f"expected a NODE_COORD_SECTION (EDGE_WEIGHT_TYPE "
                                           f"{ewt})")
            weights = distance_matrix(coordinates, ewt).astype(float)
        precedence: list[tuple[int, int]] = []
        for a, b, number in self.ordering:
            if a == b:
                raise self.error(number, f"expected set {a} before other sets, not itself")
            precedence.append((a - 1, b - 1))
        if precedence and kind != "PCGLNS":
            raise self.error(self.ordering_line, f"expected GTSP_SET_ORDERING only in a "
                                                 f"PCGLNS file, TYPE is {kind}")
        start = None
        if self.start is not None:
            start, number = self.start
            for a, b in precedence:
                if b == start:
                    raise self.error(self.ordering_line, f"expected the start set {start + 1}"
                                                         f" before every set, the ordering "
                                                         f"puts set {a + 1} before it")
        from subtask_opt.tour.constraints import find_cycle

        cycle = find_cycle(precedence)
        if cycle is not None:
            raise self.error(self.ordering_line, "expected an ordering without cycles, got "
                             + " -> ".join(str(c + 1) for c in cycle))
        name = self.header.get("NAME", (default_name, 0))[0] or default_name or "unnamed"
        w = weights
        w.setflags(write=False)
        sets = self.sets
        sets.setflags(write=False)
        if coordinates is not None:
            coordinates.setflags(write=False)
        return GtspInstance(name=name, problem_type=kind, edge_weight_type=ewt, weights=w,
                            sets=sets, coordinates=coordinates,
                            precedence=tuple(dict.fromkeys(precedence)), start=start,
                            comment="\n".join(self.comments))

    def explicit(self, kind: str, fmt: str, n: int) -> np.ndarray:
        assert self.weights is not None
        values, where, start = self.weights
        bad = np.flatnonzero(~np.isfinite(values) | (values > MAX_DISTANCE)
                             | ((values < 0) & ((values != FORBIDDEN) | (kind != "PCGLNS"))))
        if bad.size:
            k = int(bad[0])
            allowed = " or -1 (forbidden)" if kind == "PCGLNS" else ""
            raise self.error(int(where[k]), f"expected an edge weight in [0, 2**53]{allowed}, "
                                            f"got {values[k]:g}")
        values = np.where(values == FORBIDDEN, np.inf, values)
        if fmt == "FULL_MATRIX":
            m = values.reshape(n, n).copy()
        else:
            m = np.zeros((n, n))
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
        np.fill_diagonal(m, 0.0)
        if kind == "GTSP" and not np.array_equal(m, m.T):
            i, j = np.argwhere(m != m.T)[0]
            raise self.error(start, f"expected a symmetric matrix (TYPE GTSP; use AGTSP for "
                                    f"an asymmetric one): weight {i + 1} -> {j + 1} is "
                                    f"{m[i, j]:g}, {j + 1} -> {i + 1} is {m[j, i]:g}")
        return m


# --------------------------------------------------------------------------- solving

BOUND_SHARE = 0.25
"""Least share of :func:`solve_gtsp`'s time limit the lower bound may use."""
LP_BOUND_MAX_VERTICES = 300
"""The most vertices of a symmetric file whose bound also tries the LP relaxation (its
model has M^2 / 2 edge columns; building it for more would overrun the bound's time)."""
CERTIFY_MIN_S = 60.0
"""Least time :func:`solve_gtsp`'s certificate may take."""
GTSP_POPULATION = 8
"""Micro-GA population of :func:`solve_gtsp` (the arm problems keep 5). Every child of a
GTSPLIB search carries a large-neighbourhood search of one step per set, so a run makes
only tens of generations in GLNS's time; with 5 individuals it converges on one deep local
optimum (132d657 at twice GLNS's time: 22533 from 8 seeds of 8), with 8 it keeps enough
variety to leave it (22498-22501 from 4 of 8), and 12 or more make too few generations
(benchmarks/gtsplib.py --population)."""


def gtsp_params(runs: int | None = None) -> Any:
    """The :class:`~subtask_opt.tour.solve.SolverParams` of :func:`solve_gtsp`: ``runs``
    independent runs (None: the solver's default), :data:`GTSP_POPULATION`, no bound inside
    the search (the bound is computed after it, in the time left)."""
    from subtask_opt.tour.solve import SolverParams

    return SolverParams(runs=runs, bound_max_nodes=0, population=GTSP_POPULATION)


@dataclass(frozen=True)
class GtspSolution:
    """A tour of a :class:`GtspInstance`, its cost from the file's weights and a bound.

    Attributes:
        name: the instance's name.
        tour: 0-based vertices in visiting order, one of every set (the file's ids are
            ``tour + 1``), from the start set when the file names one.
        cost: the closed tour's cost recomputed from the file's weights.
        lower_bound: no tour is cheaper: the Held-Karp bound of the cheapest arcs between
            the sets (a relaxation without the precedence), or, if higher, for symmetric
            files up to :data:`LP_BOUND_MAX_VERTICES` vertices, the LP relaxation of the
            vertex model with generalised cuts (:func:`~subtask_opt.tour.exact.gtsp_lp_bound`)
            in the time the bound gets.
        runtime_s: wall time of the search, the bound and the certificate together
            (numba's compilation never included).
        search_runtime_s, bound_runtime_s: the search's and the bound's part.
        seed: the solver seed.
        generations, runs: what the micro-GA did.
        certified: the certificate's outcome (``--certify``), or None.
    """

    name: str
    tour: np.ndarray
    cost: float
    lower_bound: float
    runtime_s: float
    search_runtime_s: float
    bound_runtime_s: float
    seed: int
    generations: int
    runs: int
    certified: str | None = None

    @property
    def gap(self) -> float:
        """``(cost - lower_bound) / lower_bound``: the tour is at most this far above the
        optimum (0: proven optimal)."""
        if self.lower_bound <= 0:
            return 0.0 if self.cost <= 0 else math.inf
        return max(0.0, (self.cost - self.lower_bound) / self.lower_bound)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``tour`` in the file's numbering; timings in the ``*runtime_s`` keys."""
        return {"name": self.name, "tour": [int(v) + 1 for v in self.tour],
                "cost": _number(self.cost), "lower_bound": _number(self.lower_bound),
                "gap": self.gap, "certified": self.certified, "seed": self.seed,
                "generations": self.generations, "runs": self.runs,
                "runtime_s": self.runtime_s, "search_runtime_s": self.search_runtime_s,
                "bound_runtime_s": self.bound_runtime_s}


def solve_gtsp(instance: GtspInstance, *, time_limit: float = 10.0, seed: int = 0,
               runs: int | None = None, certify: bool = False, progress: bool = False,
               stop: Any = None) -> GtspSolution:
    """Solve ``instance`` with :func:`subtask_opt.tour.solve.solve` and bound its gap.

    The search (``runs`` independent micro-GA runs, default
    :meth:`~subtask_opt.tour.solve.SolverParams.default_runs`) stops at ``stop`` (default:
    the solver's own stall criterion) or after ``time_limit`` seconds, whichever comes
    first; then the lower bound gets what the search left of ``time_limit``, and at least
    :data:`BOUND_SHARE` of it. ``certify``: prove the tour optimal (or not) by branch and
    cut (:func:`~subtask_opt.tour.exact.gtsp_set_optimum`) within
    max(``time_limit``, :data:`CERTIFY_MIN_S`) more seconds; with precedence the
    certificate is not available. The tour itself depends on the machine's speed only when
    the time limit ends the search.
    """
    from subtask_opt.base.errors import NoPathError, require_positive
    from subtask_opt.base.stop import MaxRuntime, as_criteria
    from subtask_opt.tour.bound import lower_bound
    from subtask_opt.tour.configurations import penalty_for_legs
    from subtask_opt.tour.solve import solve

    if not isinstance(instance, GtspInstance):
        raise ParameterError(f"solve_gtsp needs a GtspInstance, got {type(instance).__name__}")
    require_positive("solve_gtsp", "time_limit", time_limit)
    require_int("solve_gtsp", "seed", seed, 0, 2**63 - 1)
    problem = instance.problem()
    constraints = instance.constraints()
    params = gtsp_params(runs)
    configured = not (constraints is not None and constraints.precedence)
    base = as_criteria(stop, params.default_stop(problem.size, configured=configured))
    result = solve(problem, seed=seed, params=params, progress=progress,
                   constraints=constraints, stop=[*base, MaxRuntime(float(time_limit))])
    assert result.configurations is not None
    order = np.asarray(result.order, dtype=np.int64)
    tour = np.asarray(result.configurations, dtype=np.int64)[order]
    cost = instance.tour_cost(tour)
    if not math.isfinite(cost):
        raise NoPathError(f"{instance.name}: no tour found that avoids the forbidden arcs")
    broken = instance.violations(tour)
    if broken:  # the operators keep every rule: a bug, never an answer
        raise InputDataError(f"internal error: the tour breaks {broken[0]}")
    lower_bound(np.ones((3, 3)) - np.eye(3), iterations=1)  # compiled before the clock
    bound_started = time.perf_counter()
    search_s = result.runtime_s  # after compilation
    budget = max(time_limit - search_s, BOUND_SHARE * time_limit)
    m = np.array(problem.matrix)
    m[~np.isfinite(m)] = penalty_for_legs(m, problem.size)
    bound = min(lower_bound(m, upper=max(cost, 1e-9) if cost > 0 else None, seed=seed,
                            time_limit=budget), cost)
    left = budget - (time.perf_counter() - bound_started)
    if (left > 0 and problem.vertex_count <= LP_BOUND_MAX_VERTICES and problem.symmetric
            and np.all(np.isfinite(problem.weights))):
        from subtask_opt.base.errors import SubtaskOptError
        from subtask_opt.tour.exact import gtsp_lp_bound

        try:  # the LP relaxation over the vertices: far tighter where the sets overlap
            bound = max(bound, min(gtsp_lp_bound(problem.weights, problem.sets,
                                                 time_limit=left), cost))
        except SubtaskOptError:
            pass  # no LP solved in the time left: the Held-Karp bound stands
    bound_s = time.perf_counter() - bound_started
    certified = None
    if certify:
        certified = _certificate(instance, problem, tour, cost,
                                 max(time_limit, CERTIFY_MIN_S))
        if certified == "optimal (proven)":
            bound = cost
    done = time.perf_counter()
    return GtspSolution(name=instance.name, tour=tour, cost=cost, lower_bound=float(bound),
                        runtime_s=search_s + done - bound_started, search_runtime_s=search_s,
                        bound_runtime_s=bound_s, seed=int(seed),
                        generations=int(result.generations), runs=int(result.runs),
                        certified=certified)


def _certificate(instance: GtspInstance, problem: Any, tour: np.ndarray, cost: float,
                 time_limit: float) -> str:
    from subtask_opt.base.errors import SubtaskOptError
    from subtask_opt.tour.exact import gtsp_set_optimum

    if instance.precedence:
        return "not certified: the certificate takes no precedence"
    try:
        optimum, _ = gtsp_set_optimum(problem, incumbent=tour, time_limit=time_limit)
    except SubtaskOptError as exc:
        return f"not certified: {exc}"
    if cost <= optimum * (1 + 1e-9) + 1e-12:
        return "optimal (proven)"
    return f"not optimal: the proven optimum is {optimum:.10g}"


def _number(value: float) -> float | int:
    """A whole float as an int (GTSPLIB costs are integers)."""
    return int(value) if math.isfinite(value) and value == int(value) else value
