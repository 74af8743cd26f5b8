"""GridWorld: construction from text, arrays, PNG and MovingAI files; reading a
file by content; size limits; validation."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from subtask_opt.base.errors import InputDataError, ParameterError, UnreachableError
from subtask_opt.planners.grid import world as world_module
from subtask_opt.planners.grid.maps import (
    MAP_NAMES,
    THESIS_CELL_SIZE,
    THESIS_MAPS,
    UNBORDERED,
    thesis_case,
)
from subtask_opt.planners.grid.world import MAX_SIDE, GridWorld, read_grid


def test_from_ascii_characters_and_indexing():
    w = GridWorld.from_ascii("""
        .G#
        S@.
        TOW
    """)
    assert (w.width, w.height) == (3, 3)
    assert w.occupancy.tolist() == [[False, False, True], [False, True, False],
                                    [True, True, True]]
    assert w.is_free(1, 0) and not w.is_free(2, 0) and not w.is_free(1, 1)
    assert not w.is_free(-1, 0) and not w.is_free(3, 0) and not w.is_free(0, 3)


@pytest.mark.parametrize("text, where", [(".x.", "row 0, col 1"), ("..\n.?", "row 1, col 1")])
def test_from_ascii_unknown_character(text, where):
    with pytest.raises(InputDataError, match=where):
        GridWorld.from_ascii(text)


def test_from_ascii_ragged_and_empty():
    with pytest.raises(InputDataError, match="row 1"):
        GridWorld.from_ascii("...\n..")
    with pytest.raises(InputDataError, match="empty"):
        GridWorld.from_ascii("   ")


def test_from_array_converts_and_is_read_only():
    w = GridWorld.from_array([[0, 1], [1, 0]], cell_size=0.5, name="x")
    assert w.occupancy.dtype == bool and w.cell_size == 0.5
    with pytest.raises(ValueError):
        w.occupancy[0, 0] = True


@pytest.mark.parametrize("bad", [np.zeros(3), np.zeros((0, 2)), [[0, 2]], [["a"]]])
def test_from_array_rejects(bad):
    with pytest.raises(InputDataError):
        GridWorld.from_array(bad)


@pytest.mark.parametrize("size", [0, -1.0, float("nan"), True])
def test_cell_size_must_be_positive(size):
    with pytest.raises(ParameterError, match="cell_size"):
        GridWorld(np.zeros((2, 2), bool), cell_size=size)


def test_check_cell_errors_name_label_and_value():
    w = GridWorld.from_ascii("..\n.#")
    assert w.check_cell("start", (0, 1)) == (0, 1)
    assert w.check_cell("start", (1.0, 0.0)) == (1, 0)
    with pytest.raises(UnreachableError, match=r"goal \(1, 1\) is on an obstacle"):
        w.check_cell("goal", (1, 1))
    with pytest.raises(UnreachableError, match=r"start \(5, 0\) is outside"):
        w.check_cell("start", (5, 0))
    with pytest.raises(UnreachableError, match="start must be a cell"):
        w.check_cell("start", (0.5, 0))
    with pytest.raises(UnreachableError, match="goal must be a cell"):
        w.check_cell("goal", "ab")
    with pytest.raises(UnreachableError, match="goal must be a cell"):
        w.check_cell("goal", (1, 2, 3))


def test_with_border():
    w = GridWorld.from_ascii("..\n..").with_border()
    assert w.occupancy.shape == (4, 4)
    assert w.occupancy[0].all() and w.occupancy[:, 0].all() and not w.occupancy[1:3, 1:3].any()


def test_from_png(tmp_path):
    img = np.full((3, 4), 255, dtype=np.uint8)
    img[1, 2] = 0
    img[2, 0] = 100
    Image.fromarray(img).save(tmp_path / "m.png")
    w = GridWorld.from_png(tmp_path / "m.png")
    assert w.occupancy.tolist() == [[False] * 4, [False, False, True, False],
                                    [True, False, False, False]]
    assert w.name == "m"
    (tmp_path / "bad.png").write_text("not an image")
    with pytest.raises(InputDataError, match="cannot read image"):
        GridWorld.from_png(tmp_path / "bad.png")
    with pytest.raises(InputDataError, match="image file not found"):
        GridWorld.from_png(tmp_path / "missing.png")


def test_from_movingai_real_map(movingai_dir):
    w = GridWorld.from_movingai(movingai_dir / "maps" / "arena.map")
    assert (w.width, w.height) == (49, 49) and w.name == "arena"
    rows = (movingai_dir / "maps" / "arena.map").read_text().splitlines()[4:]
    for y in (0, 1, 10, 48):
        for x in range(49):
            assert w.is_free(x, y) == (rows[y][x] in ".GS")


@pytest.mark.parametrize("text, match", [
    ("type octile\nheight 2\nwidth 2\n", "no 'map' line"),
    ("type octile\nheight 3\nwidth 2\nmap\n..\n..\n", "height 3, found 2"),
    ("type octile\nheight 2\nwidth 3\nmap\n..\n..\n", "width 3"),
    ("type octile\nheight x\nwidth 2\nmap\n..\n..\n", "integer 'height'"),
    ("type octile\nheight 2\nwidth 2\nmap\n..\n.q\n", "unknown map character 'q'"),
    ("type octile extra\nheight 2\nwidth 2\nmap\n..\n..\n", "bad header"),
])
def test_from_movingai_malformed(tmp_path, text, match):
    f = tmp_path / "bad.map"
    f.write_text(text)
    with pytest.raises(InputDataError, match=match):
        GridWorld.from_movingai(f)


def test_from_movingai_missing_file(tmp_path):
    with pytest.raises(InputDataError, match="map not found"):
        GridWorld.from_movingai(tmp_path / "none.map")


def test_thesis_maps_shape_border_and_difficulty():
    from subtask_opt.planners.grid.distance_transform import plan_mdt

    lengths = []
    for name in MAP_NAMES:
        case = thesis_case(name)
        w = case.world
        bordered = name not in UNBORDERED
        assert case.border == int(bordered)
        assert (w.width, w.height) == ((16, 11) if bordered else (14, 9))
        assert w.cell_size == THESIS_CELL_SIZE
        assert w.is_free(*case.start) and w.is_free(*case.goal)
        if bordered:
            assert w.occupancy[0].all() and w.occupancy[-1].all()
        raw = thesis_case(name, border=False)
        assert (raw.world.width, raw.world.height) == (14, 9)
        assert np.array_equal(raw.world.occupancy, w.occupancy[case.border:w.height - case.border,
                                                               case.border:w.width - case.border])
        if name in THESIS_MAPS:
            lengths.append(plan_mdt(w, case.start, case.goal).length)
    # rising difficulty: the cluttered map is the longest detour
    assert lengths[-1] == max(lengths)
    with pytest.raises(ParameterError, match="unknown map 'nope'"):
        thesis_case("nope")


def test_read_grid_decides_by_content(tmp_path, movingai_dir):
    img = np.full((2, 3), 255, dtype=np.uint8)
    img[0, 1] = 0
    Image.fromarray(img).save(tmp_path / "image.txt", format="PNG")  # a PNG, any suffix
    (tmp_path / "ascii.map").write_text("..#\n...\n")  # ASCII whatever the suffix
    (tmp_path / "movingai.png").write_text("type octile\nheight 1\nwidth 2\nmap\n.@\n")
    assert read_grid(tmp_path / "image.txt").occupancy.tolist() == [[False, True, False],
                                                                     [False, False, False]]
    assert read_grid(tmp_path / "ascii.map").occupancy.tolist() == [[False, False, True],
                                                                     [False, False, False]]
    assert read_grid(tmp_path / "movingai.png").occupancy.tolist() == [[False, True]]
    real = read_grid(movingai_dir / "maps" / "arena.map")
    assert np.array_equal(real.occupancy,
                          GridWorld.from_movingai(movingai_dir / "maps" / "arena.map").occupancy)


@pytest.mark.parametrize("data, match", [
    (b"\xff\xfe\x00garbage", "not a text file"),
    (b"\x89PNG\r\n\x1a\nbroken", "cannot read image"),
    (b"", "empty"),
    (b"type octile\nheight 99999\nwidth 2\nmap\n", "over the limit"),
    (b"..\n.x\n", "unknown map character 'x'"),
])
def test_read_grid_bad_content(tmp_path, data, match):
    f = tmp_path / "bad"
    f.write_bytes(data)
    with pytest.raises(InputDataError, match=match):
        read_grid(f)


def test_size_limits(tmp_path, monkeypatch):
    wide = "." * (MAX_SIDE + 1)
    with pytest.raises(InputDataError, match=f"{MAX_SIDE}x{MAX_SIDE}"):
        GridWorld.from_ascii(wide)
    img = np.full((1, 9), 255, dtype=np.uint8)
    Image.fromarray(img).save(tmp_path / "wide.png")
    monkeypatch.setattr(world_module, "MAX_SIDE", 8)
    with pytest.raises(InputDataError, match="9x1 grid is over the limit"):
        GridWorld.from_png(tmp_path / "wide.png")
    monkeypatch.setattr(world_module, "MAX_FILE_BYTES", 10)
    (tmp_path / "big.txt").write_text("." * 11)
    with pytest.raises(InputDataError, match="has 11 bytes; the limit is 10"):
        read_grid(tmp_path / "big.txt")
