"""Tour shapes and precedence constraints, and how they become a closed-tour problem.

A real job is not always a closed tour over the subtasks. :class:`TourConstraints`
says which shape the answer must have:

* ``tour="closed"`` (the default): a closed tour that starts (and ends) at
  ``start`` (default: the problem's ``first``, else subtask 0);
* ``tour="open"``: a path from ``start`` (default 0) to ``end`` (a fixed
  subtask, or ``None``: wherever is best); the robot does not come back;
* ``home``: a pose that is not a subtask, visited first and last (a closed
  tour through the home and every subtask). For an arm problem it is a point
  ``(x, y)`` the arm must reach; for a matrix problem it is the index of the
  matrix row/column that is the home (that node is then not a subtask and
  does not appear in ``order``);
* ``precedence``: pairs ``(a, b)``: subtask ``a`` is done before subtask ``b``
  (0-based indices into the input rows, as in ``order``).

All shapes reduce to one *canonical* problem (:class:`Canonical`): a closed
tour over a (possibly asymmetric) matrix whose first node is pinned, whose last
node may be pinned, and whose positions respect the precedence pairs.

* An open path with a free end is a closed tour over the matrix whose column
  ``start`` is zero: the return leg to ``start`` is free, so every closed tour
  costs exactly its open path (a zero-cost return).
* An open path with a fixed end pins ``end`` to the last position and makes
  the leg ``end -> start`` free.
* A home is one more node (the arm's home point appended as row N; a matrix's
  home row as it is), pinned first; the answer's ``order`` leaves it out.

The answer is reported in the user's terms (:meth:`Canonical.user_order`,
:meth:`Canonical.user_legs`): no home in ``order``, and ``total_time``
without the free return leg of an open path.

A lower bound of the canonical matrix ignoring the pins and the precedence is a
bound of a relaxation, hence a valid lower bound of the constrained problem.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError

TOUR_KINDS = ("closed", "open")
MAX_PAIRS = 1_000_000
"""The most precedence pairs one problem may have."""


def _index(value: object, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ParameterError(f"TourConstraints.{what} must be a non-negative integer index, "
                             f"got {value!r}")
    return int(value)


@dataclass(frozen=True)
class TourConstraints:
    """The shape of the answer and the order constraints between subtasks.

    Attributes:
        tour: ``"closed"`` (return to the start) or ``"open"`` (a path).
        start: the subtask the tour or path starts at (default: the problem's
            ``first``, else 0). Not with ``home``.
        end: the subtask an open path ends at (``None``: free), or the last one before
            the home of a closed tour (a planar arm's home point, a serial arm's home).
        home: a home the tour starts at and, closed, returns to (an open path from
            the home ends at its last subtask): an ``(x, y)`` point for a planar arm
            problem, a node index for a matrix problem.
        precedence: pairs ``(a, b)``, subtask ``a`` before subtask ``b``
            (stored as a tuple of int pairs; checked acyclic on construction).
    """

    tour: str = "closed"
    start: int | None = None
    end: int | None = None
    home: tuple[float, float] | int | None = None
    precedence: tuple[tuple[int, int], ...] = ()

    def __post_init__(self) -> None:
        if self.tour not in TOUR_KINDS:
            raise ParameterError(f"TourConstraints.tour must be one of {', '.join(TOUR_KINDS)}, "
                                 f"got {self.tour!r}")
        if self.start is not None:
            object.__setattr__(self, "start", _index(self.start, "start"))
        if self.end is not None:
            object.__setattr__(self, "end", _index(self.end, "end"))
            if self.start is not None and self.end == self.start:
                raise ParameterError(f"TourConstraints: an open path from subtask {self.start} "
                                     f"to itself is a closed tour; use tour='closed'")
        if self.home is not None:
            object.__setattr__(self, "home", _home_value(self.home))
            if self.start is not None:
                raise ParameterError(f"TourConstraints: home and start={self.start} contradict "
                                     "each other (with a home the tour starts at the home)")
        pairs = _pairs(self.precedence)
        object.__setattr__(self, "precedence", pairs)
        cycle = find_cycle(pairs)
        if cycle is not None:
            raise InputDataError("precedence constraints form a cycle: "
                                 + " -> ".join(str(v) for v in cycle))

    @property
    def is_plain(self) -> bool:
        """Whether this is today's closed tour without home or precedence."""
        return self.tour == "closed" and self.home is None and not self.precedence

    def check_size(self, n: int, *, matrix_home: bool, own_home: bool = False) -> None:
        """Raise if an index is out of 0..n-1 or the options contradict each other.

        ``n`` counts the problem's subtasks (matrix problems: its nodes, home
        included); ``matrix_home`` says the home must be a node index; ``own_home``
        that the problem has a home of its own (a serial arm's home configuration).
        """
        if (self.tour == "closed" and self.end is not None and self.home is None
                and not own_home):
            raise ParameterError(f"TourConstraints.end={self.end} needs tour='open' or a "
                                 "home (a closed tour ends where it starts)")
        top = n - 1
        for name in ("start", "end"):
            v = getattr(self, name)
            if v is not None and v > top:
                raise InputDataError(f"TourConstraints.{name} is subtask {v}; subtasks are "
                                     f"numbered 0..{top}")
        home = self.home
        if home is not None:
            if matrix_home and not isinstance(home, int):
                raise ParameterError(f"a matrix problem's home is a node index in 0..{top}, "
                                     f"got the point {home!r}")
            if not matrix_home and isinstance(home, int):
                raise ParameterError(f"an arm problem's home is a point (x, y), got the "
                                     f"index {home}")
            if isinstance(home, int) and home > top:
                raise InputDataError(f"TourConstraints.home is node {home}; nodes are "
                                     f"numbered 0..{top}")
        for a, b in self.precedence:
            for v in (a, b):
                if v > top:
                    raise InputDataError(f"precedence ({a}, {b}) names subtask {v}; subtasks "
                                         f"are numbered 0..{top}")
                if isinstance(home, int) and v == home:
                    raise ParameterError(f"precedence ({a}, {b}) names node {v}, which is the "
                                         "home (always first and last)")
        start, end = self.start, self.end
        for a, b in self.precedence:
            if start is not None and b == start:
                raise ParameterError(f"precedence ({a}, {b}) asks for a subtask before the "
                                     f"start {start}")
            if end is not None and a == end:
                raise ParameterError(f"precedence ({a}, {b}) asks for a subtask after the "
                                     f"end {end}")

    def describe(self) -> dict[str, Any]:
        """The JSON view: ``tour``, ``start``, ``end``, ``home`` (``precedence`` count apart)."""
        home: Any = self.home
        if isinstance(home, tuple):
            home = [float(home[0]), float(home[1])]
        return {"tour": self.tour, "start": self.start, "end": self.end, "home": home}


def checked(constraints: object, first: int | None = None) -> TourConstraints:
    """``constraints`` validated (None: a plain closed tour), refusing a home together with
    a problem's own first node ``first`` (with a home the tour starts at the home)."""
    if constraints is None:
        constraints = TourConstraints()
    elif not isinstance(constraints, TourConstraints):
        raise ParameterError(f"solve: constraints must be a TourConstraints, got "
                             f"{constraints!r}")
    if first is not None and constraints.home is not None:
        raise ParameterError(f"the problem's first={first} and a home contradict each other "
                             "(with a home the tour starts at the home)")
    return constraints


def _home_value(home: object) -> tuple[float, float] | int:
    if isinstance(home, (int, np.integer)) and not isinstance(home, bool):
        return _index(home, "home")
    try:
        xy = np.asarray(home, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"TourConstraints.home must be a point (x, y) or a node index, "
                             f"got {home!r}") from None
    if xy.shape != (2,) or not np.all(np.isfinite(xy)):
        raise ParameterError(f"TourConstraints.home must be a finite point (x, y) or a node "
                             f"index, got {home!r}")
    return float(xy[0]), float(xy[1])


def _pairs(precedence: object) -> tuple[tuple[int, int], ...]:
    if isinstance(precedence, np.ndarray):
        precedence = precedence.tolist()
    if isinstance(precedence, (str, bytes)) or not isinstance(precedence, Iterable):
        raise ParameterError(f"TourConstraints.precedence must be a list of pairs (a, b), "
                             f"got {precedence!r}")
    out: list[tuple[int, int]] = []
    seen: set[tuple[int, int]] = set()
    for item in precedence:
        if isinstance(item, (str, bytes)) or not isinstance(item, Sequence) or len(item) != 2:
            raise ParameterError(f"a precedence constraint is a pair (a, b), got {item!r}")
        a, b = (_index(v, "precedence") for v in item)
        if a == b:
            raise InputDataError(f"precedence ({a}, {b}) puts subtask {a} before itself")
        if (a, b) not in seen:
            seen.add((a, b))
            out.append((a, b))
        if len(out) > MAX_PAIRS:
            raise InputDataError(f"more than {MAX_PAIRS} precedence constraints")
    return tuple(out)


def find_cycle(pairs: Sequence[tuple[int, int]]) -> list[int] | None:
    """A cycle ``[v0, v1, ..., v0]`` of the precedence graph, or None (iterative DFS)."""
    succ: dict[int, list[int]] = {}
    for a, b in pairs:
        succ.setdefault(a, []).append(b)
    state: dict[int, int] = {}  # 1 on the stack, 2 done
    for root in sorted(succ):
        if state.get(root):
            continue
        stack = [(root, 0)]
        path = [root]
        state[root] = 1
        while stack:
            v, k = stack[-1]
            nxt = succ.get(v, [])
            if k < len(nxt):
                stack[-1] = (v, k + 1)
                w = nxt[k]
                s = state.get(w, 0)
                if s == 1:
                    return path[path.index(w):] + [w]
                if s == 0:
                    state[w] = 1
                    stack.append((w, 0))
                    path.append(w)
            else:
                state[v] = 2
                stack.pop()
                path.pop()
    return None


MAX_INDEX_DIGITS = 9
"""The most digits a subtask index of a precedence file may have."""


def read_precedence(path: str | Path, *, size: int | None = None) -> tuple[tuple[int, int], ...]:
    """Precedence pairs from a text file: one ``a,b`` per line (``#`` comments, blank lines ok).

    Each index is ASCII digits (at most :data:`MAX_INDEX_DIGITS`; no superscripts, no
    Arabic-Indic or full-width digits), and with ``size`` below it. A pair of a subtask with
    itself, a pair given twice and a cycle are refused; every error names the file and the
    line (a cycle: its subtasks and the lines of its pairs).

    Raises:
        InputDataError: the first problem found, in one line.
    """
    from subtask_opt.base.files import read_text

    text = read_text(Path(path), what="precedence file")
    pairs: list[tuple[int, int]] = []
    line_of: dict[tuple[int, int], int] = {}
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        parts = [p.strip() for p in line.split(",")]
        shown = raw.strip()[:60]
        if len(parts) != 2 or not all(p.isascii() and p.isdigit() for p in parts):
            raise InputDataError(f"{path}: line {number}: expected 'a,b' (two non-negative "
                                 f"subtask indices in ASCII digits), got {shown!r}")
        if any(len(p) > MAX_INDEX_DIGITS for p in parts):
            raise InputDataError(f"{path}: line {number}: an index of more than "
                                 f"{MAX_INDEX_DIGITS} digits in {shown!r}")
        a, b = int(parts[0]), int(parts[1])
        if a == b:
            raise InputDataError(f"{path}: line {number}: '{a},{b}' puts subtask {a} before "
                                 "itself")
        if size is not None and max(a, b) >= size:
            raise InputDataError(f"{path}: line {number}: '{a},{b}' names subtask "
                                 f"{max(a, b)}; subtasks are numbered 0..{size - 1}")
        if (a, b) in line_of:
            raise InputDataError(f"{path}: line {number}: '{a},{b}' repeats line "
                                 f"{line_of[(a, b)]}")
        line_of[(a, b)] = number
        pairs.append((a, b))
        if len(pairs) > MAX_PAIRS:
            raise InputDataError(f"{path}: line {number}: more than {MAX_PAIRS} precedence "
                                 "constraints")
    cycle = find_cycle(pairs)
    if cycle is not None:
        edges = list(zip(cycle, cycle[1:], strict=False))
        lines = ", ".join(str(line_of[e]) for e in edges[:20]) + (", ..." if len(edges) > 20
                                                                  else "")
        members = " -> ".join(str(v) for v in cycle[:21]) + (" -> ..." if len(cycle) > 21
                                                               else "")
        raise InputDataError(f"{path}: lines {lines} form a cycle of {len(edges)} subtasks: "
                             f"{members}")
    return tuple(pairs)


@dataclass(frozen=True)
class Canonical:
    """A constrained problem as a closed tour with pins: what the GA and the oracles solve.

    Attributes:
        matrix: the (M, M) canonical costs (read-only).
        first: the node pinned to position 0.
        last: the node pinned to position M - 1, or -1.
        pairs: (P, 2) int64 precedence pairs in canonical node indices.
        open_path: the return leg is free (not part of the user's total).
        home: the home node (left out of the user's order), or -1.
    """

    matrix: np.ndarray
    first: int
    last: int
    pairs: np.ndarray
    open_path: bool
    home: int

    @property
    def size(self) -> int:
        return int(self.matrix.shape[0])

    @property
    def needs_pins(self) -> bool:
        """Whether plain closed-tour search (rotating to ``first`` afterwards) is not enough."""
        return self.last >= 0 or self.pairs.shape[0] > 0

    def user_order(self, tour: np.ndarray) -> np.ndarray:
        """The canonical tour (starting at ``first``) as the user's order (no home)."""
        t = np.asarray(tour, dtype=np.int64)
        return t[1:].copy() if self.home >= 0 else t.copy()

    def user_legs(self, original: np.ndarray, tour: np.ndarray) -> np.ndarray:
        """The legs the robot drives, from the user's ``original`` costs (home included).

        Closed tour or home: M legs (the last one back to the start or home);
        open path: M - 1 legs (no return).
        """
        t = np.asarray(tour, dtype=np.int64)
        if self.open_path:
            return np.asarray(original)[t[:-1], t[1:]]
        return np.asarray(original)[t, np.roll(t, -1)]

    def violations(self, tour: np.ndarray) -> list[str]:
        """What the canonical ``tour`` breaks (empty: it is feasible)."""
        return tour_violations(tour, self.first, self.last, self.pairs)


def tour_violations(tour: np.ndarray, first: int, last: int, pairs: np.ndarray) -> list[str]:
    """Broken pins and precedence pairs of ``tour`` (a permutation)."""
    t = np.asarray(tour, dtype=np.int64)
    out = []
    if t[0] != first:
        out.append(f"starts at {t[0]}, not {first}")
    if last >= 0 and t[-1] != last:
        out.append(f"ends at {t[-1]}, not {last}")
    pos = np.empty(len(t), dtype=np.int64)
    pos[t] = np.arange(len(t))
    for a, b in np.asarray(pairs, dtype=np.int64).reshape(-1, 2):
        if pos[a] > pos[b]:
            out.append(f"{b} comes before {a}")
    return out


def canonical(matrix: np.ndarray, constraints: TourConstraints, *, default_start: int,
              home_index: int | None = None) -> Canonical:
    """The canonical closed-tour form of ``matrix`` under ``constraints``.

    Args:
        matrix: the user's (M, M) costs (for an arm problem with a home point,
            the matrix with the home appended as node ``home_index``).
        constraints: validated against M (see :meth:`TourConstraints.check_size`).
        default_start: the start when ``constraints.start`` is None.
        home_index: the home node (an arm's appended row); a matrix problem's
            home is ``constraints.home``.
    """
    m = np.array(matrix, dtype=float)
    home = home_index if home_index is not None else (
        constraints.home if isinstance(constraints.home, int) else None)
    pairs = np.array(constraints.precedence, dtype=np.int64).reshape(-1, 2)
    last = -1
    open_path = constraints.tour == "open"
    if home is not None:
        first = int(home)
    else:
        first = constraints.start if constraints.start is not None else int(default_start)
    if open_path:
        if constraints.end is not None:
            last = int(constraints.end)
            if last == first:
                raise ParameterError(f"an open path from subtask {first} to itself is a "
                                     "closed tour; use tour='closed'")
            m[last, first] = 0.0
        else:
            m[:, first] = 0.0
    elif constraints.end is not None:  # the last subtask before the home
        last_visit = int(constraints.end)
        before = [(v, last_visit) for v in range(m.shape[0]) if v not in (first, last_visit)]
        pairs = np.unique(np.vstack([pairs, np.array(before, dtype=np.int64).reshape(-1, 2)]),
                          axis=0)
    for a, b in pairs:
        if b == first:
            raise ParameterError(f"precedence ({a}, {b}) asks for a subtask before the "
                                 f"start {first}")
    m.setflags(write=False)
    return Canonical(matrix=m, first=first, last=last, pairs=pairs, open_path=open_path,
                     home=-1 if home is None else int(home))


def transform_tensor(tensor: np.ndarray, canon: Canonical) -> np.ndarray:
    """The (N, K, N, K) per-configuration leg times with the free return leg of ``canon``."""
    t = np.array(tensor, dtype=float)
    if canon.open_path:
        if canon.last >= 0:
            t[canon.last, :, canon.first, :] = 0.0
        else:
            t[:, :, canon.first, :] = 0.0
    return t


def symmetric_path_matrix(costs: np.ndarray, start: int, end: int | None,
                          ) -> tuple[np.ndarray, float]:
    """An open path over symmetric ``costs`` as a symmetric closed tour: ``(matrix, offset)``.

    One dummy node D (the last row) joins the path's ends: ``D - start`` costs 0,
    ``D - end`` costs 0 for a fixed end and ``K`` for a free one, every other edge
    at D costs ``K``, where ``K`` exceeds the cost of a feasible path. A tour that
    does not enter D from the path's ends pays at least one ``K`` more than one
    that does, so the shortest tour is the shortest path plus ``offset`` (``K``
    for a free end, 0 for a fixed one). This keeps the strong symmetric
    Held-Karp bound and the subtour-cut MILP for open paths (the zero-cost
    return of :func:`canonical` makes the costs asymmetric).
    """
    c = np.asarray(costs, dtype=float)
    n = c.shape[0]
    order = [start] + [v for v in range(n) if v not in (start, end)]
    if end is not None:
        order.append(end)
    k = float(np.sum(c[order[:-1], order[1:]])) + 1.0
    m = np.full((n + 1, n + 1), k)
    m[:n, :n] = c
    m[n, n] = 0.0
    m[n, start] = m[start, n] = 0.0
    if end is not None:
        m[n, end] = m[end, n] = 0.0
    return m, (0.0 if end is not None else k)
