"""The offline HTML tour view: embedded data against Pinocchio FK, validation, and a real
headless Chromium that loads the page, draws frame 0 and takes a screenshot."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from subtask_opt.base.errors import ParameterError
from subtask_opt.cell.scene import Box, Scene
from subtask_opt.kinematics.serial import load_serial_arm
from subtask_opt.plotting.arm3d import (
    LINK_COLOUR,
    frame_indices,
    tour_view_data,
    write_tour_html,
)

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
Q0 = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])
Q1 = np.array([1.0, -1.0, 1.2, -1.8, -1.57, 0.5])


@pytest.fixture(scope="module")
def ur5():
    return load_serial_arm("ur5")


def _tour(steps: int = 300) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0.0, 3.0, steps)
    s = (t / t[-1])[:, None]
    return t, Q0 + (Q1 - Q0) * s


def _scene() -> Scene:
    return Scene(boxes=(Box(name="panel", center=np.array([0.5, 0.3, 0.2]),
                            half_extents=np.array([0.2, 0.2, 0.01]), rotation=np.eye(3)),))


def _embedded(path: Path) -> dict:
    text = path.read_text(encoding="utf-8")
    match = re.search(r'<script type="application/json" id="tour-data">(.*?)</script>', text,
                      re.S)
    assert match is not None
    return json.loads(match.group(1))


def test_embedded_points_are_the_forward_kinematics(ur5, tmp_path):
    t, q = _tour(50)
    out = write_tour_html(tmp_path / "v.html", ur5, t, q, targets=[[0.5, 0.3, 0.22]],
                          axes=[[0, 0, -2]], scene=_scene(), title="t")
    data = _embedded(out)
    frames = np.array(data["frames"]).reshape(len(t), data["n_points"], 3)
    assert data["n_points"] == ur5.nq + 2  # base, joints, tool
    # tool point = the tool frame's FK (a different Pinocchio entry point), base at 0
    tool = np.array([ur5.fk(qk)[:3, 3] for qk in q])
    np.testing.assert_allclose(frames[:, -1], tool, atol=6e-5)
    np.testing.assert_allclose(frames[:, 0], 0.0, atol=1e-12)
    # the shoulder pan joint sits on the base z axis at the URDF's height, whatever q
    np.testing.assert_allclose(frames[:, 1, :2], 0.0, atol=1e-12)
    np.testing.assert_allclose(data["axes"], [[0.0, 0.0, -1.0]])  # normalised
    assert data["labels"] == ["0"] and data["label_kind"] == "index"
    corners = np.array(data["boxes"][0]["corners"])
    np.testing.assert_allclose(corners.min(axis=0), [0.3, 0.1, 0.19])
    np.testing.assert_allclose(corners.max(axis=0), [0.7, 0.5, 0.21])


def test_page_is_self_contained_and_bounded(ur5, tmp_path):
    t, q = _tour(5000)
    out = write_tour_html(tmp_path / "v.html", ur5, t, q, max_frames=300)
    text = out.read_text(encoding="utf-8")
    assert "<script src" not in text and "http://" not in text and "https://" not in text
    data = _embedded(out)
    assert len(data["t"]) == 300 and data["source_frames"] == 5000
    assert data["t"][0] == 0.0 and data["t"][-1] == 3.0
    assert out.stat().st_size < 300 * (ur5.nq + 2) * 3 * 9 + 20_000


def test_targets_labelled_by_visit(ur5):
    t, q = _tour(3)
    data = tour_view_data(ur5, t, q, targets=np.zeros((4, 3)), order=[2, 0, 3, 1])
    assert data["labels"] == ["2", "4", "1", "3"] and data["label_kind"] == "visit number"


def test_title_cannot_break_out_of_the_page(ur5, tmp_path):
    t, q = _tour(3)
    out = write_tour_html(tmp_path / "v.html", ur5, t, q, title="</script><b>x</b>")
    text = out.read_text(encoding="utf-8")
    assert "<b>x</b>" not in text
    assert _embedded(out)["title"] == "</script><b>x</b>"


@pytest.mark.parametrize("count,most", [(1, 2), (10, 10), (11, 10), (12345, 2000), (7, 2)])
def test_frame_indices(count, most):
    idx = frame_indices(count, most)
    assert idx[0] == 0 and idx[-1] == count - 1
    assert len(idx) <= most and np.all(np.diff(idx) > 0)
    if count <= most:
        np.testing.assert_array_equal(idx, np.arange(count))


@pytest.mark.parametrize("kwargs,match", [
    ({"times": [0.0, 1.0, 0.5]}, "non-decreasing"),
    ({"times": [0.0, 1.0]}, r"q must have shape \(2, 6\), got \(3, 6\)"),
    ({"q": np.zeros((3, 5))}, r"q must have shape \(3, 6\)"),
    ({"q": np.full((3, 6), np.nan)}, "q must be finite"),
    ({"targets": [[0, 0]]}, "targets must have shape"),
    ({"targets": [[0, 0, 0]], "axes": [[0, 0, 0]]}, r"axes\[0\] is zero"),
    ({"axes": [[0, 0, 1]]}, "axes need targets"),
    ({"targets": [[0, 0, 0]], "axes": [[0, 0, 1], [0, 0, 1]]}, "axes must have shape"),
    ({"max_frames": 1}, "max_frames"),
    ({"scene": "panel.json"}, "scene must be a Scene"),
    ({"title": 3}, "title must be a string"),
    ({"targets": np.zeros((3, 3)), "order": [0, 1, 1]}, "order must be a permutation"),
    ({"arm": "ur5"}, "arm must be a SerialArm"),
])
def test_bad_input(ur5, kwargs, match):
    args = {"arm": ur5, "times": [0.0, 0.5, 1.0], "q": np.zeros((3, 6))}
    args.update(kwargs)
    arm, times, q = args.pop("arm"), args.pop("times"), args.pop("q")
    with pytest.raises(ParameterError, match=match):
        tour_view_data(arm, times, q, **args)


# ----------------------------------------------------------------- real browser

def _chromium(url: str, profile: Path, *extra: str) -> subprocess.CompletedProcess:
    assert CHROMIUM is not None
    return subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--no-first-run", f"--user-data-dir={profile}", "--window-size=1000,700",
         "--virtual-time-budget=3000", *extra, url],
        capture_output=True, text=True, timeout=120, check=False)


needs_chromium = pytest.mark.skipif(
    CHROMIUM is None, reason="chromium not installed (Debian: apt-get install chromium; "
                             ".ci/run installs it)")


@pytest.fixture(scope="module")
def page(ur5, tmp_path_factory) -> Path:
    t, q = _tour()
    folder = tmp_path_factory.mktemp("view")
    return write_tour_html(folder / "tour.html", ur5, t, q,
                           targets=[[0.5, 0.3, 0.22], [0.4, 0.2, 0.22]],
                           axes=[[0, 0, -1], [0, 0, -1]], scene=_scene(), title="UR5 test tour")


def _status(dom: str) -> tuple[str, str]:
    match = re.search(r'<span id="status" data-ok="([^"]*)">([^<]*)<', dom)
    assert match is not None, dom[-2000:]
    return match.group(1), match.group(2)


@needs_chromium
def test_browser_renders_frame_zero(page, tmp_path):
    run = _chromium(page.as_uri(), tmp_path / "profile", "--dump-dom")
    assert run.returncode == 0, run.stderr[-2000:]
    assert _status(run.stdout) == ("1", "rendered frame 0 of 300 frames")


@needs_chromium
def test_browser_reports_a_script_failure(page, tmp_path):
    """The status check can fail: corrupt data makes the page say so."""
    broken = tmp_path / "broken.html"
    text = page.read_text(encoding="utf-8")
    broken.write_text(text.replace('"n_points":8', '"n_points":9'), encoding="utf-8")
    run = _chromium(broken.as_uri(), tmp_path / "profile", "--dump-dom")
    ok, message = _status(run.stdout)
    assert ok == "0" and message == "error: malformed tour data"


@needs_chromium
def test_browser_screenshot_shows_the_arm(page, tmp_path):
    from PIL import Image

    shot = tmp_path / "shot.png"
    run = _chromium(page.as_uri(), tmp_path / "profile", f"--screenshot={shot}")
    assert run.returncode == 0 and shot.is_file(), run.stderr[-2000:]
    img = np.asarray(Image.open(shot).convert("RGB")).astype(np.int64)
    assert img.shape[:2] == (700, 1000)
    assert img.std() > 10  # not blank
    link = np.array([int(LINK_COLOUR[i:i + 2], 16) for i in (1, 3, 5)])
    arm_pixels = np.all(np.abs(img - link) <= 12, axis=2)
    assert arm_pixels.sum() > 2000  # the links are thick bands of the link colour
    rows, cols = np.nonzero(arm_pixels)
    assert cols.max() - cols.min() > 100 and rows.max() - rows.min() > 100  # spread out
    # the panel's faces: light, bluish grey
    box_pixels = (img[..., 2] > img[..., 0] + 10) & (img[..., 2] < 230) & (img[..., 0] > 120)
    assert box_pixels.sum() > 2000


@needs_chromium
def test_browser_opens_at_a_time_from_the_address(page, tmp_path):
    run = _chromium(page.as_uri() + "#t=1.5", tmp_path / "profile", "--dump-dom")
    times = np.array(_embedded(page)["t"])
    shown = times[times <= 1.5].max()  # the last frame not after t
    match = re.search(r'<span id="clock">([^<]*)<', run.stdout)
    assert match is not None and match.group(1) == f"t = {shown:.3f} s / 3.000 s"
    assert _status(run.stdout)[0] == "1"


@needs_chromium
def test_browser_draws_the_arm_where_it_is_at_that_time(page, tmp_path):
    """The arm drawn at t = 3 s is not the arm at t = 0 (the animation data is used)."""
    from PIL import Image

    link = np.array([int(LINK_COLOUR[i:i + 2], 16) for i in (1, 3, 5)])
    masks = []
    for k, suffix in enumerate(("", "#t=3")):
        shot = tmp_path / f"shot{k}.png"
        _chromium(page.as_uri() + suffix, tmp_path / f"profile{k}", f"--screenshot={shot}")
        img = np.asarray(Image.open(shot).convert("RGB")).astype(np.int64)
        masks.append(np.all(np.abs(img - link) <= 12, axis=2))
    moved = np.logical_xor(masks[0], masks[1]).sum()
    assert moved > 0.3 * min(masks[0].sum(), masks[1].sum())
