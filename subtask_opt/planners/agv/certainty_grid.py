"""Certainty grid from an image, and the AGV's 2-bit local-map states (seed 004).

Rule 1-1 of the paper: the image is cut into square blocks of ``cell_px`` x
``cell_px`` pixels (10 x 10 in the paper, so a 400 x 400 image gives a 40 x 40
map); the certainty value ``C(i, j)`` of a cell is its count of set pixels, and
the cell is an obstacle in the global map when that count exceeds the density
factor. A pixel is *set* when it is darker than ``threshold`` (the grid world's
PNG convention: dark = obstacle); a boolean array is taken as already set/unset.

The local map gives each cell two bits ``b1 b2``:

* ``00`` :data:`FREE` - no set pixel; the only routable state,
* ``01`` :data:`MIXED` - some set pixels, but not above the density factor
  (free and obstacle space mixed; access restricted),
* ``10`` :data:`APPROACHABLE` - an obstacle cell with a non-obstacle neighbour
  (impassable, but the AGV may come up to it),
* ``11`` :data:`INACCESSIBLE` - an obstacle cell surrounded by obstacle cells.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError, require_in_range, require_int
from subtask_opt.planners.grid.world import GridWorld

MAX_IMAGE_PIXELS = 4_000_000
"""Images larger than this (2000 x 2000 pixels) are refused before decoding."""

FREE = 0b00
MIXED = 0b01
APPROACHABLE = 0b10
INACCESSIBLE = 0b11
STATE_NAMES = {FREE: "free", MIXED: "mixed", APPROACHABLE: "approachable",
               INACCESSIBLE: "inaccessible"}


@dataclass(frozen=True)
class CertaintyParams:
    """How an image becomes a certainty grid.

    Attributes:
        cell_px: side of a cell in pixels (paper: 10).
        density_factor: a cell is an obstacle when more than this many of its
            ``cell_px**2`` pixels are set; in ``[0, cell_px**2 - 1]``.
        threshold: grey level in (0, 1]; darker pixels are set.
    """

    cell_px: int = 10
    density_factor: int = 30
    threshold: float = 0.5

    def __post_init__(self) -> None:
        require_int("CertaintyParams", "cell_px", self.cell_px, 1)
        require_int("CertaintyParams", "density_factor", self.density_factor, 0)
        if self.density_factor > self.cell_px ** 2 - 1:
            raise ParameterError(
                f"CertaintyParams.density_factor must be in [0, {self.cell_px ** 2 - 1}] "
                f"(cells of {self.cell_px}x{self.cell_px} pixels), got {self.density_factor!r}")
        require_in_range("CertaintyParams", "threshold", self.threshold, 1e-9, 1.0)


@dataclass(frozen=True)
class CertaintyGrid:
    """Certainty values of an image and the maps derived from them.

    Attributes:
        counts: int array ``[y, x]``, set pixels per cell (``C(i, j)``).
        params: the parameters used.
    """

    counts: np.ndarray
    params: CertaintyParams

    @property
    def occupancy(self) -> np.ndarray:
        """Global map (rule 1-1): ``True`` where ``counts > density_factor``."""
        return self.counts > self.params.density_factor

    def local_states(self) -> np.ndarray:
        """The 2-bit local-map state of every cell (uint8 ``[y, x]``)."""
        return local_map_states(self.counts, self.params.density_factor)

    def world(self, name: str = "", *, routable_only: bool = False) -> GridWorld:
        """The grid world of the global map (cell size = ``cell_px`` pixels).

        With ``routable_only`` every cell that is not :data:`FREE` is blocked
        (the paper's rule that only ``00`` cells are routable).
        """
        occ = routable(self.local_states()) != 0 if routable_only else self.occupancy
        return GridWorld(occ, float(self.params.cell_px), name)


def read_pixels(source: Any, threshold: float = 0.5) -> np.ndarray:
    """Set pixels of an image as a bool array ``[row, col]``.

    ``source`` is a path to an image file (PNG, ...), a bool array (``True`` =
    set), or a numeric grey / RGB(A) array, 0..1 floats or 0..255 integers
    (set = darker than ``threshold``).

    Raises:
        InputDataError: the file cannot be read, the array is empty, not 2-D
            (or 3-D with 3/4 channels), or holds non-finite values.
    """
    if isinstance(source, (str, Path)):
        from PIL import Image, UnidentifiedImageError

        path = Path(source)
        try:
            with Image.open(path) as img:
                w, h = img.size
                if w * h > MAX_IMAGE_PIXELS:
                    raise InputDataError(
                        f"image {str(path)!r} has {w}x{h} pixels; at most {MAX_IMAGE_PIXELS} "
                        f"are read")
                rgba = np.asarray(img.convert("RGBA"), dtype=float) / 255.0
        except (OSError, UnidentifiedImageError, ValueError, Image.DecompressionBombError) \
                as exc:
            if isinstance(exc, InputDataError):
                raise
            raise InputDataError(f"cannot read image {str(path)!r}: {exc}") from None
        if rgba.size == 0:
            raise InputDataError(f"image {str(path)!r} is empty")
        grey = rgba[..., :3] @ np.array([0.299, 0.587, 0.114])
        return (grey < threshold) & (rgba[..., 3] >= 0.5)
    arr = np.asarray(source)
    if arr.size == 0:
        raise InputDataError(f"image array is empty (shape {arr.shape})")
    if arr.dtype == np.bool_:
        if arr.ndim != 2:
            raise InputDataError(f"a bool image must be 2-D, got shape {arr.shape}")
        return arr.copy()
    if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise InputDataError(f"image array must hold numbers or bools, got dtype {arr.dtype}")
    arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        raise InputDataError("image array holds non-finite values")
    if arr.ndim == 3 and arr.shape[2] in (3, 4):
        grey = arr[..., :3] @ np.array([0.299, 0.587, 0.114])
    elif arr.ndim == 2:
        grey = arr
    else:
        raise InputDataError(
            f"image array must be (H, W) or (H, W, 3|4), got shape {arr.shape}")
    if grey.max() > 1.0:
        grey = grey / 255.0
    return grey < threshold


def certainty_counts(pixels: np.ndarray, cell_px: int) -> np.ndarray:
    """Set pixels per ``cell_px`` x ``cell_px`` block (the certainty values).

    Raises:
        InputDataError: the image is smaller than one cell or its sides are not
            multiples of ``cell_px``.
    """
    h, w = pixels.shape
    if h < cell_px or w < cell_px or h % cell_px or w % cell_px:
        raise InputDataError(
            f"image of {w}x{h} pixels cannot be cut into {cell_px}x{cell_px}-pixel cells "
            f"(both sides must be positive multiples of {cell_px})")
    blocks = pixels.reshape(h // cell_px, cell_px, w // cell_px, cell_px)
    return blocks.sum(axis=(1, 3)).astype(np.int64)


def certainty_grid(source: Any, params: CertaintyParams | None = None) -> CertaintyGrid:
    """Read an image (path or array) and count its set pixels per cell."""
    params = CertaintyParams() if params is None else params
    pixels = read_pixels(source, params.threshold)
    return CertaintyGrid(certainty_counts(pixels, params.cell_px), params)


def grid_from_image(source: Any, params: CertaintyParams | None = None,
                    name: str = "") -> GridWorld:
    """Global map of an image as a :class:`GridWorld` (rule 1-1)."""
    if not name and isinstance(source, (str, Path)):
        name = Path(source).stem
    return certainty_grid(source, params).world(name)


def local_map_states(counts: np.ndarray, density_factor: int) -> np.ndarray:
    """2-bit state of each cell from its certainty value (see module docs)."""
    counts = np.asarray(counts)
    blocked = counts > density_factor
    padded = np.pad(blocked, 1, constant_values=True)
    h, w = blocked.shape
    # an obstacle cell is approachable when one of its 4 neighbours is not an obstacle
    open_nb = np.zeros_like(blocked)
    for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        open_nb |= ~padded[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]
    states = np.full(blocked.shape, FREE, dtype=np.uint8)
    states[(counts > 0) & ~blocked] = MIXED
    states[blocked & open_nb] = APPROACHABLE
    states[blocked & ~open_nb] = INACCESSIBLE
    return states


def routable(states: np.ndarray) -> np.ndarray:
    """``b1 OR b2`` of each cell (uint8): 0 where the AGV may route, 1 elsewhere."""
    states = np.asarray(states)
    return ((states >> 1) | (states & 1)).astype(np.uint8)
