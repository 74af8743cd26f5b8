"""The figures of a real cell: meshes, the tool on its frame and detoured legs, in the HTML
view (embedded data against Pinocchio FK, a headless Chromium) and the matplotlib figure."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from subtask_opt.base.errors import ParameterError
from subtask_opt.cell.meshes import Mesh, box_triangles, write_stl
from subtask_opt.cell.scene import Box, Scene, Tool
from subtask_opt.kinematics.serial import load_serial_arm
from subtask_opt.plotting.arm3d import tour_view_data, write_tour_html
from subtask_opt.plotting.cell_geometry import DetourLeg, detour_legs, simplified
from tests.plotting.test_arm3d import _chromium, _embedded, _status, needs_chromium

Q0 = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])
Q1 = np.array([1.0, -1.0, 1.2, -1.8, -1.57, 0.5])
QW = np.array([0.5, -1.9, 1.0, -1.0, -1.57, 0.2])  # a detour's waypoint
DRILL = Box(name="drill", center=np.array([0.0, 0.0, 0.06]),
            half_extents=np.array([0.02, 0.02, 0.06]), rotation=np.eye(3))
PILLAR = np.array([0.45, -0.3, 0.25])


@pytest.fixture(scope="module")
def ur5():
    return load_serial_arm("ur5")


@pytest.fixture(scope="module")
def scene(tmp_path_factory) -> Scene:
    folder = tmp_path_factory.mktemp("cellview")
    write_stl(folder / "pillar.stl", *box_triangles([0.04, 0.04, 0.25]))
    pillar = Mesh(name="pillar", file=folder / "pillar.stl", position=PILLAR)
    return Scene(meshes=(pillar,), tool=Tool(frame="tool0", boxes=(DRILL,)))


def _tour(steps: int = 200) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0.0, 2.0, steps)
    s = (t / t[-1])[:, None]
    return t, Q0 + (Q1 - Q0) * s


def _detour() -> DetourLeg:
    return DetourLeg(0, 0.5, 1.5, np.array([Q0, QW, Q1]))


def test_meshes_tool_and_detours_are_embedded_where_fk_puts_them(ur5, scene) -> None:
    t, q = _tour(20)
    data = tour_view_data(ur5, t, q, scene=scene, detours=[_detour()])
    mesh = data["meshes"][0]
    v = np.array(mesh["vertices"]).reshape(-1, 3)
    corners = np.array([[x, y, z] for x in (-0.04, 0.04) for y in (-0.04, 0.04)
                        for z in (-0.25, 0.25)]) + PILLAR  # the pillar, placed by hand
    assert mesh["name"] == "pillar" and len(mesh["triangles"]) == 36
    assert max(np.linalg.norm(v - c, axis=1).min() for c in corners) < 1e-4
    tool = data["tool"]
    assert tool["frame"] == "tool0" and len(tool["poses"]) == len(t)
    tool0 = load_serial_arm("ur5", tool_frame="tool0")  # the frame by another entry point
    for k in (0, 7, 19):
        pose = np.array(tool["poses"][k])
        want = tool0.fk(q[k])
        np.testing.assert_allclose(pose[:9].reshape(3, 3), want[:3, :3], atol=1e-5)
        np.testing.assert_allclose(pose[9:], want[:3, 3], atol=1e-5)
    part = np.array(tool["parts"][0]["vertices"]).reshape(-1, 3)  # in the frame of tool0
    np.testing.assert_allclose(part.min(axis=0), [-0.02, -0.02, 0.0], atol=1e-9)
    np.testing.assert_allclose(part.max(axis=0), [0.02, 0.02, 0.12], atol=1e-9)
    det = data["detours"][0]
    assert det["t"] == [0.5, 1.5]
    np.testing.assert_allclose(det["corners"], [ur5.fk(w)[:3, 3] for w in (Q0, QW, Q1)],
                               atol=6e-5)


def test_simplified_mesh_stays_near_the_mesh_and_within_the_count() -> None:
    # a fine sphere (about 10 000 triangles): the picture keeps its shape
    n = 72
    theta, phi = np.meshgrid(np.linspace(0, np.pi, n), np.linspace(0, 2 * np.pi, n),
                             indexing="ij")
    v = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)],
                 -1).reshape(-1, 3)
    tris = [(i * n + j, (i + 1) * n + j, (i + 1) * n + j + 1) for i in range(n - 1)
            for j in range(n - 1)] + [(i * n + j, (i + 1) * n + j + 1, i * n + j + 1)
                                      for i in range(n - 1) for j in range(n - 1)]
    out_v, out_t, cell = simplified(v, np.array(tris), 500)
    assert 12 <= len(out_t) <= 500 and cell > 0
    assert out_t.min() >= 0 and out_t.max() < len(out_v)
    # every kept vertex is a mean of the sphere's vertices in one cell: near the sphere
    assert np.abs(np.linalg.norm(out_v, axis=1) - 1.0).max() < np.sqrt(3) * cell
    # and every original vertex has a kept vertex within one cell's diagonal
    d = np.linalg.norm(v[:, None] - out_v[None], axis=2).min(axis=1)
    assert d.max() <= np.sqrt(3) * cell
    same = simplified(v, np.array(tris), 20_000)
    assert same[2] == 0.0 and len(same[1]) == len(tris)


def test_bad_detours_are_refused(ur5) -> None:
    t, q = _tour(3)
    with pytest.raises(ParameterError, match=r"detours\[0\] must be a DetourLeg"):
        tour_view_data(ur5, t, q, detours=[np.zeros((3, 6))])
    with pytest.raises(ParameterError, match=r"waypoints must be finite with shape"):
        tour_view_data(ur5, t, q, detours=[DetourLeg(0, 0.0, 1.0, np.zeros((3, 5)))])
    with pytest.raises(ParameterError, match="must end after it starts"):
        tour_view_data(ur5, t, q, detours=[DetourLeg(0, 1.0, 0.5, np.zeros((3, 6)))])
    with pytest.raises(ParameterError, match="detour_legs: a Trajectory is needed"):
        detour_legs("trajectory")


# ----------------------------------------------------------------- real browser

@pytest.fixture(scope="module")
def page(ur5, scene, tmp_path_factory) -> Path:
    t, q = _tour()
    return write_tour_html(tmp_path_factory.mktemp("view") / "cell.html", ur5, t, q,
                           targets=[[0.45, -0.3, 0.5]], scene=scene, detours=[_detour()])


@needs_chromium
def test_status_line_follows_the_animation(page, tmp_path) -> None:
    times = np.array(_embedded(page)["t"])
    for k, at in enumerate((None, 0.7, 1.9)):
        run = _chromium(page.as_uri() + ("" if at is None else f"#t={at}"),
                        tmp_path / f"profile{k}", "--dump-dom")
        frame = 0 if at is None else int(np.nonzero(times <= at)[0].max())
        assert _status(run.stdout) == ("1", f"rendered frame {frame} of {len(times)} frames")


def _pixels(shot: Path, rgb: tuple[int, int, int], tol: int) -> np.ndarray:
    from PIL import Image

    img = np.asarray(Image.open(shot).convert("RGB")).astype(np.int64)
    return np.all(np.abs(img - np.array(rgb)) <= tol, axis=2)


@needs_chromium
def test_browser_draws_the_mesh_the_tool_and_the_detour(page, tmp_path) -> None:
    masks = {}
    for k, suffix in enumerate(("", "#t=2")):
        shot = tmp_path / f"shot{k}.png"
        _chromium(page.as_uri() + suffix, tmp_path / f"p{k}", f"--screenshot={shot}")
        # the tool: orange (245, 159, 0) shaded by 0.55..1; purple detour path (156, 54, 181)
        from PIL import Image

        img = np.asarray(Image.open(shot).convert("RGB")).astype(np.int64)
        r, g, b = img[..., 0], img[..., 1], img[..., 2]
        masks[k] = (r > 120) & (b < 40) & (np.abs(g - 0.65 * r) < 25)
        if k == 1:
            assert _pixels(shot, (156, 54, 181), 10).sum() > 100  # the executed detour
        # the pillar: the mesh colour (170, 180, 135) shaded, over white
        assert ((g > r) & (r > b + 20) & (b > 60)).sum() > 800
    assert masks[0].sum() > 30 and masks[1].sum() > 30
    assert np.logical_xor(masks[0], masks[1]).sum() > 0.5 * min(masks[0].sum(), masks[1].sum())


# ----------------------------------------------------------------- matplotlib figure

def test_figure_draws_meshes_tool_and_detours_in_equal_axes(ur5, scene) -> None:
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from subtask_opt.plotting.serial import DETOUR_COLOUR, serial_tour_figure

    targets = np.array([[0.45, -0.3, 0.55], [0.4, 0.2, 0.2]])
    path = np.array([ur5.fk(Q0)[:3, 3], *targets, ur5.fk(Q0)[:3, 3]])
    fig = serial_tour_figure(ur5, targets, path, np.ones(3), np.array([0, 1]), q_home=Q0,
                             scene=scene, detours=[DetourLeg(1, 0.0, 1.0,
                                                             np.array([Q0, QW, Q1]))])
    ax3, _, bar = fig.axes
    polys = [c for c in ax3.collections if isinstance(c, Poly3DCollection)]
    labels = [c.get_label() for c in polys]
    assert labels == ["scene meshes", "tool on tool0"]
    # the drill at home: its far end is tool0's origin + 0.12 m along tool0's z
    home = load_serial_arm("ur5", tool_frame="tool0").fk(Q0)
    tip = home[:3, 3] + 0.12 * home[:3, 2]
    verts = np.asarray(polys[1]._faces).reshape(-1, 3)  # the 3-D triangles given
    assert np.linalg.norm(verts - tip, axis=1).min() < 0.03  # a corner by the tip
    line = [ln for ln in ax3.get_lines() if ln.get_color() == DETOUR_COLOUR][0]
    xyz = np.array(line.get_data_3d()).T
    np.testing.assert_allclose(xyz[0], ur5.fk(Q0)[:3, 3], atol=1e-9)
    np.testing.assert_allclose(xyz[-1], ur5.fk(Q1)[:3, 3], atol=1e-9)
    assert [p.get_facecolor()[:3] for p in bar.patches][1] != bar.patches[0].get_facecolor()[:3]
    # equal axes that contain the pillar
    lims = np.array([ax3.get_xlim(), ax3.get_ylim(), ax3.get_zlim()])
    np.testing.assert_allclose(np.diff(lims, axis=1)[:, 0], np.diff(lims, axis=1)[0, 0])
    top = PILLAR + [0.04, 0.04, 0.25]
    assert np.all(lims[:, 0] <= PILLAR - [0.04, 0.04, 0.25] + 1e-9)
    assert np.all(lims[:, 1] >= top - 1e-9)
    plt.close(fig)


def test_figure_refuses_a_detour_of_no_leg(ur5) -> None:
    from subtask_opt.plotting.serial import serial_tour_figure

    with pytest.raises(ParameterError, match=r"detours\[0\]\.index must be a leg number"):
        serial_tour_figure(ur5, np.zeros((2, 3)), np.zeros((4, 3)), np.ones(3),
                           np.array([0, 1]), detours=[DetourLeg(3, 0.0, 1.0,
                                                                np.array([Q0, Q1]))])


def test_status_text_in_the_page_is_the_frame_counter_only(page) -> None:
    script = page.read_text(encoding="utf-8")
    assert re.search(r'"rendered frame " \+ frame \+ " of " \+ T', script)
