"""Occupancy grids for the grid planners.

A :class:`GridWorld` is a boolean array ``occupancy[y, x]`` (``True`` = blocked)
with a cell size in world units. Coordinates follow the MovingAI convention:
``x`` is the column, ``y`` the row, both 0-based from the top-left corner.
Every grid planner works in cell coordinates ``(x, y)``.

Grids come from ASCII text (MovingAI characters), a numpy array, a PNG image
(dark pixels blocked) or a MovingAI ``.map`` file; :func:`read_grid` reads any
of the three files, deciding the format by content. Files over
:data:`MAX_FILE_BYTES` (64 MiB) or grids over :data:`MAX_SIDE` (4096) cells a
side are refused with an :class:`InputDataError`, as is any malformed content.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base import files
from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    UnreachableError,
    require_positive,
)

#: MovingAI characters: passable and blocked terrain.
FREE_CHARS = frozenset(".GS")
BLOCKED_CHARS = frozenset("#@OTW")


@dataclass(frozen=True, eq=False)
class GridWorld:
    """An occupancy grid (compared and hashed by identity, as it holds an array).

    Attributes:
        occupancy: bool array of shape (height, width); ``True`` = blocked;
            indexed ``[y, x]``. Stored read-only.
        cell_size: length of a cell side in world units (the thesis: 0.03 m).
        name: a label for tables and plots.
    """

    occupancy: np.ndarray
    cell_size: float = 1.0
    name: str = ""

    def __post_init__(self) -> None:
        occ = np.asarray(self.occupancy)
        if occ.ndim != 2:
            raise InputDataError(
                f"GridWorld.occupancy must be a 2-D array, got shape {occ.shape}")
        if occ.shape[0] < 1 or occ.shape[1] < 1:
            raise InputDataError(
                f"GridWorld.occupancy must be at least 1x1, got shape {occ.shape}")
        if occ.dtype != np.bool_:
            if not (np.issubdtype(occ.dtype, np.integer) or np.issubdtype(occ.dtype, np.floating)):
                raise InputDataError(
                    f"GridWorld.occupancy must hold bools or 0/1 numbers, got dtype {occ.dtype}")
            bad = ~np.isin(occ, (0, 1))
            if bad.any():
                y, x = np.argwhere(bad)[0]
                raise InputDataError(
                    f"GridWorld.occupancy must hold 0/1 values, got {occ[y, x]!r} "
                    f"at x={x}, y={y}")
            occ = occ.astype(bool)
        occ = np.array(occ, dtype=bool, copy=True)
        occ.setflags(write=False)
        object.__setattr__(self, "occupancy", occ)
        if isinstance(self.cell_size, bool):
            raise ParameterError(
                f"GridWorld.cell_size must be a number > 0, got {self.cell_size!r}")
        require_positive("GridWorld", "cell_size", self.cell_size)
        object.__setattr__(self, "cell_size", float(self.cell_size))
        if not isinstance(self.name, str):
            raise ParameterError(f"GridWorld.name must be a string, got {self.name!r}")

    # -- shape and queries -------------------------------------------------------------
    @property
    def width(self) -> int:
        """Number of columns (x range)."""
        return int(self.occupancy.shape[1])

    @property
    def height(self) -> int:
        """Number of rows (y range)."""
        return int(self.occupancy.shape[0])

    @property
    def free(self) -> np.ndarray:
        """Bool array ``[y, x]``, ``True`` where the cell is passable."""
        return ~self.occupancy

    def in_bounds(self, x: int, y: int) -> bool:
        """Whether cell ``(x, y)`` lies inside the grid."""
        return 0 <= x < self.width and 0 <= y < self.height

    def is_free(self, x: int, y: int) -> bool:
        """Whether cell ``(x, y)`` is inside the grid and passable."""
        return self.in_bounds(x, y) and not bool(self.occupancy[y, x])

    def check_cell(self, label: str, xy: Any) -> tuple[int, int]:
        """Validate a cell given as ``(x, y)``; return it as two ints.

        Raises:
            UnreachableError: naming ``label`` and the value when ``xy`` is not
                two integers, lies outside the grid, or is blocked.
        """
        try:
            vals = [float(v) for v in xy]
        except (TypeError, ValueError):
            raise UnreachableError(f"{label} must be a cell (x, y) of two integers, got {xy!r}") \
                from None
        if len(vals) != 2 or not all(np.isfinite(v) and v == int(v) for v in vals):
            raise UnreachableError(f"{label} must be a cell (x, y) of two integers, got {xy!r}")
        x, y = int(vals[0]), int(vals[1])
        if not self.in_bounds(x, y):
            raise UnreachableError(
                f"{label} ({x}, {y}) is outside the {self.width}x{self.height} grid "
                f"(x in [0, {self.width - 1}], y in [0, {self.height - 1}])")
        if self.occupancy[y, x]:
            raise UnreachableError(f"{label} ({x}, {y}) is on an obstacle")
        return x, y

    def with_border(self) -> GridWorld:
        """A copy with one blocked cell added all round (the thesis' 16x11 array).

        Cell ``(x, y)`` of this grid becomes ``(x + 1, y + 1)`` of the result.
        """
        occ = np.pad(self.occupancy, 1, constant_values=True)
        return GridWorld(occ, self.cell_size, self.name)

    def to_ascii(self) -> str:
        """The grid as MovingAI characters (``.`` free, ``@`` blocked), one row a line."""
        chars = np.where(self.occupancy, "@", ".")
        return "\n".join("".join(row) for row in chars)

    # -- constructors ------------------------------------------------------------------
    @classmethod
    def from_array(cls, array: Any, *, cell_size: float = 1.0, name: str = "") -> GridWorld:
        """From a 2-D array of bools or 0/1 numbers (``True``/1 = blocked)."""
        return cls(np.asarray(array), cell_size, name)

    @classmethod
    def from_ascii(cls, text: str, *, cell_size: float = 1.0, name: str = "") -> GridWorld:
        """From text, one row a line: ``. G S`` free, ``# @ O T W`` blocked.

        Leading/trailing blank lines and surrounding whitespace of the block
        are ignored; all rows must have the same length.
        """
        if not isinstance(text, str):
            raise InputDataError(f"map text must be a string, got {type(text).__name__}")
        return cls(_ascii_occupancy(text, "text"), cell_size, name)

    @classmethod
    def from_png(cls, path: str | Path, *, cell_size: float = 1.0, threshold: float = 0.5,
                 name: str = "") -> GridWorld:
        """From a PNG image: one pixel per cell; pixels darker than ``threshold``
        (grey level in [0, 1]) are blocked; transparent pixels are free.

        Raises:
            InputDataError: unreadable, not a PNG, over :data:`MAX_FILE_BYTES`
                or over :data:`MAX_SIDE` pixels a side.
        """
        require_positive("from_png", "threshold", threshold)
        if threshold > 1:
            raise ParameterError(f"from_png.threshold must be in (0, 1], got {threshold!r}")
        path = Path(path)
        data = read_file_bytes(path, "image")
        return cls(_png_occupancy(data, str(path), threshold), cell_size, name or path.stem)

    @classmethod
    def from_movingai(cls, path: str | Path, *, name: str | None = None) -> GridWorld:
        """From a MovingAI ``.map`` file (``type octile``, ``height``, ``width``, ``map``).

        Raises:
            InputDataError: unreadable, malformed (naming the line), over
                :data:`MAX_FILE_BYTES` or :data:`MAX_SIDE` cells a side.
        """
        path = Path(path)
        text = files.read_text(path, "map", max_bytes=MAX_FILE_BYTES)
        return cls(_movingai_occupancy(text, str(path)), 1.0, path.stem if name is None else name)


MAX_FILE_BYTES = files.MAX_FILE_BYTES
"""Map, image and scenario files larger than this (64 MiB, the package's one
file limit, :data:`subtask_opt.base.files.MAX_FILE_BYTES`) are refused."""
MAX_SIDE = 4096
"""Grids wider or taller than this many cells are refused when read from a file."""
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def read_grid(path: str | Path, *, name: str | None = None) -> GridWorld:
    """Read a grid file, deciding its format by content, never by suffix.

    * bytes starting with the PNG signature -> :meth:`GridWorld.from_png`;
    * text whose first non-blank line starts with a MovingAI header key
      (``type``, ``height``, ``width``) -> :meth:`GridWorld.from_movingai`;
    * any other text -> :meth:`GridWorld.from_ascii` (one row a line).

    Raises:
        InputDataError: unreadable, binary but not PNG, over the size limits
            (:data:`MAX_FILE_BYTES`, :data:`MAX_SIDE`), or malformed, naming
            the problem.
    """
    path = Path(path)
    data = read_file_bytes(path, "map")
    label = path.stem if name is None else name
    if data.startswith(PNG_SIGNATURE):
        return GridWorld(_png_occupancy(data, str(path), 0.5), 1.0, label)
    text = decode_text(data, str(path))
    first = next((ln.split() for ln in text.splitlines() if ln.strip()), [""])
    if first[0].lower() in ("type", "height", "width"):
        return GridWorld(_movingai_occupancy(text, str(path)), 1.0, label)
    return GridWorld(_ascii_occupancy(text, str(path)), 1.0, label)


def check_small_grid(world: GridWorld, max_free_cells: int, why: str) -> None:
    """Raise :class:`ParameterError` when ``world`` has more than ``max_free_cells``
    free cells (planners that test pairs of cells refuse big grids)."""
    n_free = int(np.count_nonzero(~world.occupancy))
    if n_free > max_free_cells:
        raise ParameterError(f"{why}; this grid has {n_free} free cells, more than "
                             f"max_free_cells={max_free_cells}")


def read_file_bytes(path: Path, what: str) -> bytes:
    """The bytes of ``path``, refusing files over :data:`MAX_FILE_BYTES` (the
    byte-level twin of :func:`subtask_opt.base.files.read_text`, for PNG images)."""
    return files.read_bytes(path, f"{what} file", max_bytes=MAX_FILE_BYTES)  # regular only


def decode_text(data: bytes, source: str) -> str:
    """UTF-8 text (a leading BOM dropped, as :func:`subtask_opt.base.files.read_text` does)."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputDataError(f"{source}: not a text file (byte {exc.start} is not UTF-8) "
                             f"and not a PNG image") from None


def _check_side(source: str, height: int, width: int) -> None:
    if height > MAX_SIDE or width > MAX_SIDE:
        raise InputDataError(f"{source}: a {width}x{height} grid is over the limit of "
                             f"{MAX_SIDE}x{MAX_SIDE} cells")


def _png_occupancy(data: bytes, source: str, threshold: float) -> np.ndarray:
    """PNG bytes -> bool array (dark, opaque pixels blocked)."""
    import io

    from PIL import Image

    if not data.startswith(PNG_SIGNATURE):
        raise InputDataError(f"cannot read image {source!r}: not a PNG file")
    try:
        with Image.open(io.BytesIO(data), formats=["PNG"]) as img:
            width, height = img.size
            _check_side(source, height, width)
            rgba = np.asarray(img.convert("RGBA"), dtype=float) / 255.0
    except InputDataError:
        raise
    except Exception as exc:  # noqa: BLE001 - a decoder fails in many ways on bad bytes
        raise InputDataError(f"cannot read image {source!r}: {type(exc).__name__}: "
                             f"{str(exc)[:120]}") from None
    if rgba.ndim != 3 or rgba.shape[0] < 1 or rgba.shape[1] < 1:
        raise InputDataError(f"cannot read image {source!r}: empty image")
    grey = rgba[..., :3] @ np.array([0.299, 0.587, 0.114])
    return (grey < threshold) & (rgba[..., 3] >= 0.5)


def _ascii_occupancy(text: str, source: str) -> np.ndarray:
    lines = [ln.strip() for ln in text.strip().splitlines()]
    if len(lines) > MAX_SIDE or (lines and max(len(ln) for ln in lines) > MAX_SIDE):
        raise InputDataError(f"{source}: more than {MAX_SIDE} rows or columns "
                             f"(limit {MAX_SIDE}x{MAX_SIDE} cells)")
    return _parse_rows(lines, source, 1)


def _movingai_occupancy(text: str, source: str) -> np.ndarray:
    """The body of a MovingAI ``.map`` file -> bool array."""
    lines = text.splitlines()
    header: dict[str, str] = {}
    i = 0
    while i < len(lines) and lines[i].strip().lower() != "map":
        parts = lines[i].split()
        if len(parts) == 2:
            header[parts[0].lower()] = parts[1]
        elif parts:
            raise InputDataError(f"{source}: line {i + 1}: bad header line {lines[i][:80]!r}")
        i += 1
    if i == len(lines):
        raise InputDataError(f"{source}: no 'map' line found")
    try:
        if not (header["height"].isascii() and header["width"].isascii()):
            raise ValueError  # int() reads Arabic-Indic digits too
        height, width = int(header["height"]), int(header["width"])
    except (KeyError, ValueError):
        shown = {k: v[:20] for k, v in list(header.items())[:4]}
        raise InputDataError(
            f"{source}: header must give integer 'height' and 'width', got {shown}") from None
    if height < 1 or width < 1:
        raise InputDataError(f"{source}: height and width must be >= 1, got {height}x{width}")
    _check_side(source, height, width)
    rows = [ln.rstrip("\r\n") for ln in lines[i + 1:]]
    while rows and not rows[-1].strip():
        rows.pop()
    if len(rows) != height:
        raise InputDataError(f"{source}: header says height {height}, found {len(rows)} rows")
    occ = _parse_rows(rows, source, i + 2)
    if occ.shape[1] != width:
        raise InputDataError(
            f"{source}: header says width {width}, rows have {occ.shape[1]} characters")
    return occ


def _parse_rows(rows: list[str], source: str, first_line: int) -> np.ndarray:
    """Rows of MovingAI characters -> bool array (``True`` = blocked)."""
    if not rows or not rows[0]:
        raise InputDataError(f"{source}: the map is empty")
    width = len(rows[0])
    for r, row in enumerate(rows):
        if len(row) != width:
            raise InputDataError(
                f"{source}: row {r} (line {first_line + r}) has {len(row)} characters, "
                f"expected {width}")
    arr = np.array(rows, dtype=f"<U{width}").view("<U1").reshape(len(rows), width)
    known = np.isin(arr, list(FREE_CHARS | BLOCKED_CHARS))
    if not known.all():
        r, c = np.argwhere(~known)[0]
        raise InputDataError(
            f"{source}: unknown map character {str(arr[r, c])!r} at row {r}, col {c} "
            f"(free: '.', 'G', 'S'; blocked: '#', '@', 'O', 'T', 'W')")
    return np.isin(arr, list(BLOCKED_CHARS))
