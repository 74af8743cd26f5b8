"""Certainty grid from images and the 2-bit local-map states (seed 004, rule 1-1)."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.planners.agv.certainty_grid import (
    APPROACHABLE,
    FREE,
    INACCESSIBLE,
    MIXED,
    CertaintyParams,
    certainty_counts,
    certainty_grid,
    grid_from_image,
    local_map_states,
    read_pixels,
    routable,
)


def _brute_counts(pixels: np.ndarray, cell: int) -> np.ndarray:
    h, w = pixels.shape
    out = np.zeros((h // cell, w // cell), dtype=int)
    for i in range(h // cell):
        for j in range(w // cell):
            for k in range(cell):
                for l_ in range(cell):
                    out[i, j] += bool(pixels[i * cell + k, j * cell + l_])
    return out


def test_counts_match_the_papers_loop():
    rng = np.random.default_rng(3)
    pixels = rng.random((30, 50)) < 0.3
    np.testing.assert_array_equal(certainty_counts(pixels, 10), _brute_counts(pixels, 10))


def test_density_factor_is_a_strict_threshold():
    img = np.ones((20, 10))  # white
    img[:10, :][np.unravel_index(np.arange(30), (10, 10))] = 0.0  # 30 dark pixels in cell 0
    img[10:, :][np.unravel_index(np.arange(31), (10, 10))] = 0.0  # 31 in cell 1
    occ = certainty_grid(img, CertaintyParams(density_factor=30)).occupancy
    assert occ.tolist() == [[False], [True]]


def test_400px_image_gives_40x40_cells_and_png_equals_array(tmp_path):
    img = np.full((400, 400), 255, dtype=np.uint8)
    img[100:250, 120:200] = 0
    path = tmp_path / "map.png"
    Image.fromarray(img).save(path)
    world = grid_from_image(path)
    assert world.occupancy.shape == (40, 40)
    assert world.name == "map" and world.cell_size == 10.0
    np.testing.assert_array_equal(world.occupancy, grid_from_image(img).occupancy)
    assert world.occupancy[10:25, 12:20].all() and world.occupancy.sum() == 15 * 8


def test_rgb_and_bool_inputs():
    rgb = np.ones((10, 20, 3))
    rgb[:, :10] = 0.0
    assert read_pixels(rgb).sum() == 100
    b = np.zeros((10, 10), dtype=bool)
    b[0, :5] = True
    assert certainty_counts(read_pixels(b), 10).item() == 5


def _brute_states(counts: np.ndarray, df: int) -> np.ndarray:
    h, w = counts.shape
    out = np.zeros((h, w), dtype=int)
    for y in range(h):
        for x in range(w):
            if counts[y, x] <= df:
                out[y, x] = FREE if counts[y, x] == 0 else MIXED
                continue
            open_nb = False
            for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
                yy, xx = y + dy, x + dx
                if 0 <= yy < h and 0 <= xx < w and counts[yy, xx] <= df:
                    open_nb = True
            out[y, x] = APPROACHABLE if open_nb else INACCESSIBLE
    return out


def test_local_states_match_brute_force_and_only_00_routes():
    rng = np.random.default_rng(7)
    counts = rng.integers(0, 100, size=(12, 9)) * (rng.random((12, 9)) < 0.6)
    states = local_map_states(counts, 30)
    np.testing.assert_array_equal(states, _brute_states(counts, 30))
    assert set(np.unique(states)) <= {0, 1, 2, 3}
    np.testing.assert_array_equal(routable(states) == 0, states == FREE)


def test_routable_only_world_blocks_mixed_cells():
    img = np.ones((20, 20))
    img[0, 0] = 0.0  # one dark pixel: a mixed cell
    cg = certainty_grid(img)
    assert not cg.occupancy.any()
    assert cg.world(routable_only=True).occupancy.tolist() == [[True, False], [False, False]]


@pytest.mark.parametrize("df", [-1, 100, 1.5, True])
def test_density_factor_out_of_range(df):
    with pytest.raises(ParameterError, match="density_factor"):
        CertaintyParams(density_factor=df)


def test_bad_threshold_and_cell_size():
    with pytest.raises(ParameterError, match="threshold"):
        CertaintyParams(threshold=1.5)
    with pytest.raises(ParameterError, match="cell_px"):
        CertaintyParams(cell_px=0)


def test_unreadable_and_empty_images(tmp_path):
    bad = tmp_path / "bad.png"
    bad.write_text("not an image")
    with pytest.raises(InputDataError, match="cannot read image"):
        certainty_grid(bad)
    with pytest.raises(InputDataError, match="cannot read image"):
        certainty_grid(tmp_path / "missing.png")
    with pytest.raises(InputDataError, match="empty"):
        certainty_grid(np.zeros((0, 0)))
    with pytest.raises(InputDataError, match="multiples"):
        certainty_grid(np.ones((405, 400)))
    with pytest.raises(InputDataError, match="non-finite"):
        certainty_grid(np.full((10, 10), np.nan))
    with pytest.raises(InputDataError, match="shape"):
        certainty_grid(np.ones((10, 10, 2)))


def test_oversize_images_are_refused_before_decoding(tmp_path):
    from subtask_opt.planners.agv.certainty_grid import MAX_IMAGE_PIXELS

    side = int(MAX_IMAGE_PIXELS ** 0.5) + 10
    path = tmp_path / "huge.png"
    Image.new("L", (side, side), 255).save(path)
    with pytest.raises(InputDataError, match=f"at most {MAX_IMAGE_PIXELS}"):
        certainty_grid(path)
