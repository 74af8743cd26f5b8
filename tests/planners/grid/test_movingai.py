"""Octile distance transform against every row of the MovingAI scenario files
(the small arena map in the unit suite, every map under ``-m bench``)."""

from __future__ import annotations

import numpy as np
import pytest

from subtask_opt.base.errors import InputDataError, UnreachableError
from subtask_opt.planners.grid.movingai import MISMATCH_TOL, bench, read_scenarios
from subtask_opt.planners.grid.world import GridWorld
from tests.conftest import REDUCED

MAPS = ("arena", "den312d", "8room_000", "random512-10-0")


def _load(movingai_dir, name):
    world = GridWorld.from_movingai(movingai_dir / "maps" / f"{name}.map")
    scen = read_scenarios(movingai_dir / "scenarios" / f"{name}.map.scen")
    return world, scen


def _rows(scen, pick):
    """The scenario rows ``pick`` as a scenario set of their own."""
    return type(scen)(scen.bucket[pick], scen.width[pick], scen.height[pick],
                      scen.start[pick], scen.goal[pick], scen.optimal[pick], scen.map_name)


@pytest.mark.parametrize("name", [
    "arena", *(pytest.param(n, marks=pytest.mark.bench) for n in MAPS if n != "arena")])
def test_every_row_matches_optimum(movingai_dir, name):
    world, scen = _load(movingai_dir, name)
    n_lines = sum(1 for ln in (movingai_dir / "scenarios" / f"{name}.map.scen")
                  .read_text().splitlines()[1:] if ln.strip())
    assert len(scen) == n_lines
    if REDUCED:  # every 25th row: the same kernels on a 25th of the sweeps
        scen = _rows(scen, np.arange(0, len(scen), 25))
    # the 512x512 files: each row's goal-rooted transform ordered towards its
    # start by exact lower bounds (A* with octile + landmark bounds: same values,
    # a fraction of the sweep); the small maps: plain early-stopped transforms.
    # Both kernels are also compared on samples below.
    report = bench(world, scen, focused=name in ("8room_000", "random512-10-0"))
    assert report.rows == len(scen)
    assert report.mismatches == 0, report.summary()
    assert report.max_abs_error <= MISMATCH_TOL


@pytest.mark.bench
@pytest.mark.parametrize("name", ["8room_000", "random512-10-0"])
def test_plain_and_focused_transforms_agree_on_a_sample(movingai_dir, name):
    world, scen = _load(movingai_dir, name)
    sample = _rows(scen, np.argsort(scen.optimal)[:: max(1, len(scen) // 12)])
    a = bench(world, sample, focused=False)
    b = bench(world, sample, focused=True)
    c = bench(world, sample, focused=True, landmarks=0)
    assert a.mismatches == 0 and np.allclose(a.ours, b.ours, atol=1e-9)
    assert np.allclose(c.ours, b.ours, atol=1e-9)


def test_read_scenarios_columns(movingai_dir):
    scen = read_scenarios(movingai_dir / "scenarios" / "arena.map.scen")
    assert scen.map_name == "maps/dao/arena.map"
    assert scen.start[0].tolist() == [1, 11] and scen.goal[0].tolist() == [1, 12]
    assert scen.optimal[2] == pytest.approx(3.41421)


@pytest.mark.parametrize("text, match", [
    ("", "version 1"),
    ("version 1\n", "no scenario rows"),
    ("version 1\n0\tm\t4\t4\t0\t0\t1\n", "expected 9 columns"),
    ("version 1\n0\tm\t4\t4\t0\t0\t1\tx\t2\n", "not a number"),
    ("version 1\n0\tm\t4\t4\t0\t0\t1\t1\t-2\n", ">= 0"),
    ("version 1\n0\tm\t4\t4\t0\t0\t1\t1\tnan\n", ">= 0"),
    ("version 1\n0\tm\t99999\t4\t0\t0\t1\t1\t2\n", "not within"),
    ("version 1\n0\tm\t4\t4\t0\t0\t9\t1\t2\n", "outside the 4x4 map"),
    ("version 1\n-1\tm\t4\t4\t0\t0\t1\t1\t2\n", "bucket"),
    ("version 1\n0\tm\t4\t4\t0\t0\t99999999999999999999999\t1\t2\n", "outside"),
])
def test_malformed_scenarios(tmp_path, text, match):
    f = tmp_path / "s.scen"
    f.write_text(text)
    with pytest.raises(InputDataError, match=match):
        read_scenarios(f)


def test_unreadable_scenarios(tmp_path):
    with pytest.raises(InputDataError, match="scenario file not found"):
        read_scenarios(tmp_path / "missing.scen")
    (tmp_path / "bin.scen").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InputDataError, match="not UTF-8 text"):
        read_scenarios(tmp_path / "bin.scen")


def test_scenario_map_mismatch_and_blocked_rows(tmp_path):
    world = GridWorld.from_ascii("...\n.#.\n...")
    f = tmp_path / "s.scen"
    f.write_text("version 1\n0\tm\t4\t4\t0\t0\t2\t2\t2.82843\n")
    with pytest.raises(InputDataError, match="4x4"):
        bench(world, read_scenarios(f))
    f.write_text("version 1\n0\tm\t3\t3\t0\t0\t1\t1\t1.41421\n")
    with pytest.raises(UnreachableError, match="row 1 goal"):
        bench(world, read_scenarios(f))
    f.write_text("version 1\n0\tm\t3\t3\t0\t0\t2\t2\t4\n0\tm\t3\t3\t0\t1\t2\t1\t4\n")
    report = bench(world, read_scenarios(f))
    assert np.array_equal(bench(world, read_scenarios(f), focused=True).ours, report.ours)
    # around the centre block: no corner cutting, so no diagonal step at all
    assert report.mismatches == 0 and report.ours.tolist() == [4.0, 4.0]
