"""The serial-arm tour figure: what it draws matches its inputs; bad inputs are refused."""

from __future__ import annotations

import numpy as np
import pytest

from subtask_opt.base.errors import ParameterError
from subtask_opt.cell.scene import Box, Scene
from subtask_opt.kinematics.serial import load_serial_arm
from subtask_opt.plotting.serial import plot_serial_tour, serial_tour_figure

HOME = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])


@pytest.fixture(scope="module")
def ur5():
    return load_serial_arm("ur5")


def _tour(arm, n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    targets = np.column_stack([rng.uniform(0.3, 0.6, n), rng.uniform(-0.2, 0.2, n),
                               np.full(n, 0.2)])
    order = rng.permutation(n)
    home = arm.fk(HOME)[:3, 3]
    path = np.vstack([home] + [targets[i] for i in order] + [home])
    return targets, path, rng.uniform(0.3, 1.2, n + 1), order


def test_figure_draws_its_inputs(ur5):
    import matplotlib.pyplot as plt

    targets, path, legs, order = _tour(ur5, 8)
    scene = Scene(boxes=(Box(name="panel", center=np.array([0.45, 0.0, 0.19]),
                             half_extents=np.array([0.2, 0.25, 0.01]), rotation=np.eye(3)),))
    fig = serial_tour_figure(ur5, targets, path, legs, order, title="UR5, 8 holes",
                             q_home=HOME, scene=scene)
    ax3, flat, bar = fig.axes
    assert fig._suptitle.get_text() == "UR5, 8 holes"
    assert (ax3.get_xlabel(), ax3.get_ylabel(), ax3.get_zlabel()) == ("x [m]", "y [m]", "z [m]")
    assert bar.get_ylabel() == "leg time [s]" and "total" in bar.get_title()
    heights = [p.get_height() for p in bar.patches]
    np.testing.assert_allclose(heights, legs)
    tool = [ln for ln in ax3.get_lines() if ln.get_label() == "tool path"][0]
    xs, ys, zs = tool.get_data_3d()
    np.testing.assert_allclose(np.column_stack([xs, ys, zs]), path)
    # every target carries its visit number at its own position
    labels = {int(t.get_text()): np.array(t.get_position_3d()) for t in ax3.texts}
    assert sorted(labels) == list(range(1, 9))
    for visit, i in enumerate(order):
        np.testing.assert_allclose(labels[visit + 1], targets[i])
    arm = [ln for ln in ax3.get_lines() if ln.get_label() == "arm at home"][0]
    np.testing.assert_allclose(np.array(arm.get_data_3d())[:, -1], ur5.fk(HOME)[:3, 3],
                               atol=1e-9)  # the drawn arm ends at the tool
    assert len([ln for ln in ax3.get_lines() if ln.get_color() == "#868e96"]) == 12
    assert bar.get_xticklabels()[0].get_text() == f"home\u2192t{order[0]}"
    assert {t.get_text() for t in ax3.get_legend().get_texts()} >= {
        "tool path", "targets (8)", "arm at home", "scene boxes"}
    plt.close(fig)


def test_many_targets_numbered_sparsely(ur5, tmp_path):
    targets, path, legs, order = _tour(ur5, 245, seed=1)
    out = plot_serial_tour(ur5, targets, path, legs, order, tmp_path / "f" / "tour.png",
                           title="245 holes")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    fig = serial_tour_figure(ur5, targets, path, legs, order)
    assert not fig.axes[0].texts  # no numbers in 3-D at this size
    numbers = sorted(int(t.get_text()) for t in fig.axes[1].texts)
    assert numbers[0] == 1 and numbers[-1] == 245 and len(numbers) <= 62
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_plane_view_keeps_distances_of_planar_targets(ur5):
    import matplotlib.pyplot as plt

    rng = np.random.default_rng(4)
    tilt = np.radians(30.0)
    u, v = np.array([np.cos(tilt), 0.0, np.sin(tilt)]), np.array([0.0, 1.0, 0.0])
    targets = np.array([0.5, 0.1, 0.2]) + np.outer(rng.uniform(-0.1, 0.1, 9), u) + \
        np.outer(rng.uniform(-0.1, 0.1, 9), v)
    order = rng.permutation(9)
    path = np.vstack([targets[order[0]], *targets[order]])
    fig = serial_tour_figure(ur5, targets, path, np.ones(10), order)
    flat = fig.axes[1]
    line = [ln for ln in flat.get_lines() if ln.get_label() == "visiting order"][0]
    uv = np.column_stack(line.get_data())
    np.testing.assert_allclose(np.linalg.norm(np.diff(uv, axis=0), axis=1),
                               np.linalg.norm(np.diff(targets[order], axis=0), axis=1))
    assert "farthest 0.0 mm off it" in flat.get_title()
    # the panel leans 30 degrees from horizontal: "up" in the picture is up the slope
    assert "v [m], along (0.87, 0.00, 0.50)" in flat.get_ylabel()
    assert "u [m], along (0.00, 1.00, 0.00)" in flat.get_xlabel()
    plt.close(fig)


@pytest.mark.parametrize("change,match", [
    ({"targets": np.zeros((0, 3))}, "at least one target"),
    ({"targets": np.zeros((3, 2))}, "targets must have shape"),
    ({"tool_path": np.zeros((1, 3))}, "at least 2 points"),
    ({"leg_times": np.ones(2)}, r"leg_times must have shape \(4,\)"),
    ({"leg_times": -np.ones(4)}, "leg_times must be >= 0"),
    ({"leg_times": np.array([1, 1, np.inf, 1])}, "leg_times must be finite"),
    ({"order": np.array([0, 0, 1])}, "order must be a permutation"),
    ({"order": np.array([0.0, 1.0, 2.0])}, "order must be a permutation"),
    ({"title": None}, "title must be a string"),
    ({"q_home": np.zeros(5)}, r"q_home must have shape \(6,\)"),
])
def test_bad_input(ur5, change, match):
    args = {"targets": np.zeros((3, 3)), "tool_path": np.zeros((5, 3)),
            "leg_times": np.ones(4), "order": np.array([2, 0, 1]), "title": "x"}
    args.update(change)
    with pytest.raises(ParameterError, match=match):
        serial_tour_figure(ur5, args.pop("targets"), args.pop("tool_path"),
                           args.pop("leg_times"), args.pop("order"), **args)
