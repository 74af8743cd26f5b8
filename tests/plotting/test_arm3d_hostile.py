"""Text from input files cannot become markup or script in the HTML tour view.

Many generated hostile strings (script tags, event-handler attributes, comment and CDATA
openers, quotes, entities, the page's own placeholders, U+2028/2029, lone surrogates) go into
every string field that reaches the page: the title, the robot name (the URDF's stem), the
scene's box and mesh names and, through the CLI, the case file's name. The oracles are
independent of the writer: Python's HTML parser must see exactly the elements and attributes
of a page written with plain names, and the strings must come back unchanged from the text
and the JSON; then headless Chromium opens such pages and none of the payloads runs (a naive
page built from the same strings shows that they would).
"""

from __future__ import annotations

import copy
import json
import os
import random
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from subtask_opt.cell.meshes import Mesh, box_triangles, write_stl
from subtask_opt.cell.scene import Box, Scene
from subtask_opt.kinematics.serial import example_robot_data_share, load_serial_arm
from subtask_opt.plotting import arm3d
from subtask_opt.plotting.arm3d import script_json, tour_view_data, write_tour_html
from tests.plotting.test_arm3d import _chromium, _status, needs_chromium

# Each would change the page if it reached it as markup or as script source.
ACTIVE = (
    "<script>document.title='PWNED'</script>",
    "</script><script>document.body.setAttribute('data-pwned','script')</script>",
    "</script><img src=x onerror=\"document.body.setAttribute('data-pwned','img')\">",
    "<img src=x onerror=\"document.body.setAttribute('data-pwned','img2')\">",
    "<svg onload=\"document.body.setAttribute('data-pwned','svg')\"></svg>",
    '<div id="pwned">injected</div>',
    "</title><div id=pwned>t</div>",
    '"><div id="pwned" data-pwned="attr">',
    "'><b id='pwned'>q</b>",
    "<!--<script>",
    "@DATA@<img src=x onerror=\"document.body.setAttribute('data-pwned','data')\">",
)
FRAGMENTS = ACTIVE + (
    "</script>", "<script>", "<!--", "-->", "<![CDATA[", "]]>", "</title>", "</div>", "<b>",
    "<", ">", '"', "'", "`", "&", "&amp;", "&lt;", "&#60;", "&#x3c;", "\\", "\\u003c", '\\"',
    "\u2028", "\u2029", "\n", "\r\n", "\t", "\x00", "\udc80", "@DATA@", "@TITLE@",
    "@LINK_COLOUR@", "${alert(1)}", "{{7*7}}", "javascript:alert(1)", "\u202e", "é", "😀", " ",
    "onerror=alert(1)", "box",
)
SPECIAL = set('<>&"\'')


def hostile(rng: random.Random) -> str:
    """One to five fragments, sometimes with plain text between them."""
    parts = [rng.choice(FRAGMENTS) for _ in range(rng.randint(1, 5))]
    return "".join(p + ("" if rng.random() < 0.6 else "x") for p in parts)


def shown(text: str) -> str:
    """What the page's text must read: lone surrogates become U+FFFD."""
    return re.sub("[\ud800-\udfff]", "\ufffd", text)


class Outline(HTMLParser):
    """Every tag with its attributes, and the text of the title, the heading and both scripts."""

    CAPTURE = {("title", None): "title", ("div", "head"): "head",
               ("script", "tour-data"): "data", ("script", None): "script"}

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple] = []
        self.text: dict[str, str] = {}
        self.ids: list[str] = []
        self.attr_names: set[str] = set()
        self._open: tuple[str, str] | None = None

    def handle_starttag(self, tag: str, attrs: list) -> None:
        self.tags.append((tag, tuple(attrs)))
        found = dict(attrs)
        self.ids += [found["id"]] if found.get("id") else []
        self.attr_names |= set(found)
        key = self.CAPTURE.get((tag, found.get("id")))
        if key is not None:
            self._open = (tag, key)
            self.text.setdefault(key, "")

    def handle_endtag(self, tag: str) -> None:
        self.tags.append(("/" + tag,))
        if self._open and self._open[0] == tag:
            self._open = None

    def handle_data(self, data: str) -> None:
        if self._open:
            self.text[self._open[1]] += data


def outline(text: str) -> Outline:
    parser = Outline()
    parser.feed(text)
    parser.close()
    return parser


@pytest.fixture(scope="module")
def ur5():
    return load_serial_arm("ur5")


def _scene(names: list[str], folder: Path | None = None) -> Scene:
    """Boxes named ``names``; with a folder, meshes of the same names too."""
    meshes: tuple[Mesh, ...] = ()
    if folder is not None:
        stl = folder / "cube.stl"
        if not stl.exists():
            write_stl(stl, *box_triangles([0.03, 0.03, 0.03]))
        meshes = tuple(Mesh(name=n, file=stl, position=[-0.5, 0.3 - 0.2 * k, 0.1])
                       for k, n in enumerate(names))
    return Scene(boxes=tuple(
        Box(name=n, center=np.array([0.5, 0.3 - 0.2 * k, 0.2]),
            half_extents=np.array([0.05, 0.05, 0.05]), rotation=np.eye(3))
        for k, n in enumerate(names)), meshes=meshes)


def _page(arm, folder: Path, tag: str, *, robot: str, title: str, boxes: list[str]) -> Path:
    named = copy.copy(arm)
    named.name = robot
    t = np.linspace(0.0, 1.0, 3)
    q = np.zeros((3, arm.nq))
    return write_tour_html(folder / f"{tag}.html", named, t, q, targets=[[0.5, 0.3, 0.2]],
                           scene=_scene(boxes, folder), title=title)


PAGES = 40


def test_generated_hostile_strings_stay_text_and_data(ur5, tmp_path) -> None:
    plain_raw = _page(ur5, tmp_path, "plain", robot="ur5", title="plain title",
                      boxes=[f"box{k}" for k in range(6)]).read_text(encoding="utf-8")
    plain = outline(plain_raw)
    rng = random.Random(20261230)
    seen = 0
    for k in range(PAGES):
        robot = hostile(rng)
        title = "" if k % 4 == 0 else hostile(rng)  # "": the title is made from the robot name
        boxes = list(dict.fromkeys(hostile(rng) for _ in range(6)))
        path = _page(ur5, tmp_path, f"p{k}", robot=robot, title=title, boxes=boxes)
        raw = path.read_bytes().decode("utf-8")  # not read_text: it would turn \r\n into \n
        page = outline(raw)
        want_title = title or f"{robot}: tour of 1 targets"
        # (a) the markup is the plain page's: no element or attribute came from the strings
        assert page.tags == plain.tags, f"page {k}: markup changed"
        assert page.text["script"] == plain.text["script"]  # the renderer, untouched
        assert page.text["title"] == page.text["head"] == shown(want_title)
        # the JSON element holds nothing the HTML parser could act on, and decodes exactly
        blob = page.text["data"]
        assert not set(blob) & {"<", ">", "&", "\u2028", "\u2029"}, f"page {k}"
        doc = json.loads(blob)
        assert doc["title"] == want_title and doc["robot"] == robot
        assert [b["name"] for b in doc["boxes"]] == boxes
        assert [m["name"] for m in doc["meshes"]] == boxes
        # outside the JSON data no string with a special character appears as written
        # (unless the plain page has it too, as "<" or "'")
        outside = raw.replace(blob, "")
        for s in [robot, title, *boxes]:
            if SPECIAL & set(s) and s not in plain_raw:
                assert s not in outside, f"page {k}: {s!r} written raw"
                seen += 1
    assert seen > 100  # the generator did produce many strings that need escaping


def test_script_json_escapes_keys_and_values() -> None:
    rng = random.Random(7)
    for _ in range(300):
        doc = {hostile(rng): [hostile(rng), {hostile(rng): hostile(rng)}] for _ in range(3)}
        text = script_json(doc)
        assert not set(text) & {"<", ">", "&", "\u2028", "\u2029"}
        assert text.isascii()
        assert json.loads(text) == doc


def test_page_script_never_inserts_markup() -> None:
    """The renderer writes strings with textContent (and canvas fillText) only."""
    script = arm3d._PAGE[arm3d._PAGE.index("<script>"):]
    for sink in ("innerHTML", "outerHTML", "insertAdjacentHTML", "document.write", "eval(",
                 "Function(", "setTimeout(\"", "setInterval(\"", "srcdoc",
                 "createContextualFragment"):
        assert sink not in script, sink
    assert "textContent" in script


# ----------------------------------------------------------------- in a real browser

def _dom(page: Path, profile: Path) -> tuple[Outline, str]:
    run = _chromium(page.as_uri(), profile, "--dump-dom")
    assert run.returncode == 0, run.stderr[-2000:]
    return outline(run.stdout), run.stdout


def _injected(dom: Outline) -> list[str]:
    """What a payload that ran or became markup leaves in the DOM."""
    out = [f"id={i}" for i in dom.ids if i == "pwned"]
    out += ["data-pwned"] if "data-pwned" in dom.attr_names else []
    out += ["title PWNED"] if dom.text.get("title") == "PWNED" else []
    return out


def _browser_strings() -> tuple[str, str, list[str]]:
    robot = "<img src=x onerror=\"document.body.setAttribute('data-pwned','robot')\">"
    title = "".join(ACTIVE[:6]) + "\u2028\u2029 &amp; \"'`"
    return robot, title, list(ACTIVE)


@needs_chromium
def test_browser_runs_none_of_the_payloads(ur5, tmp_path) -> None:
    robot, title, boxes = _browser_strings()
    for k, (r, t) in enumerate([(robot, title), (robot, "")]):
        page = _page(ur5, tmp_path, f"b{k}", robot=r, title=t, boxes=boxes)
        dom, text = _dom(page, tmp_path / f"profile{k}")
        assert _injected(dom) == []
        assert _status(text) == ("1", "rendered frame 0 of 3 frames")
        want = t or f"{r}: tour of 1 targets"
        assert dom.text["title"] == dom.text["head"] == want


@needs_chromium
def test_browser_check_sees_a_payload_that_runs(ur5, tmp_path) -> None:
    """The same strings in a page written without escaping do run: the check above can fail."""
    robot, title, boxes = _browser_strings()
    named = copy.copy(ur5)
    named.name = robot
    data = tour_view_data(named, [0.0, 1.0], np.zeros((2, ur5.nq)), scene=_scene(boxes),
                          title=title)
    naive = (arm3d._PAGE.replace("@TITLE@", title).replace("@LINK_COLOUR@", arm3d.LINK_COLOUR)
             .replace("@DATA@", json.dumps(data)))
    page = tmp_path / "naive.html"
    page.write_text(naive, encoding="utf-8")
    dom, _ = _dom(page, tmp_path / "profile")
    assert "title PWNED" in _injected(dom) and "id=pwned" in _injected(dom)


@needs_chromium
def test_cli_view_with_hostile_file_and_box_names(tmp_path, capsys) -> None:
    """``solve --view`` end to end: the robot (a URDF's stem), the case file's name (not even
    UTF-8) and the scene's box names are hostile; the page renders them as text."""
    from subtask_opt.cli import main

    urdf_src = (example_robot_data_share() / "example-robot-data" / "robots" / "ur_description"
                / "urdf" / "ur5_robot.urdf")
    (tmp_path / "example-robot-data").symlink_to(urdf_src.parents[3])  # package:// meshes
    robot = "<img src=x onerror=\"document.body.setAttribute('data-pwned','urdf')\">&'\""
    urdf = tmp_path / f"{robot}.urdf"
    urdf.write_text(urdf_src.read_text(encoding="utf-8"), encoding="utf-8")
    limits = tmp_path / "limits.json"
    limits.write_text(json.dumps({"acceleration": [3.0] * 6}))
    case = tmp_path / os.fsdecode(  # \xff: not UTF-8, a lone surrogate in the decoded name
        b"<svg onload=\"document.title='PWNED'\">@DATA@\xff" + "\u2028".encode() + b".csv")
    case.write_text("x,y,z,dx,dy,dz\n0.45,-0.15,0.20,1,0,-0.3\n0.45,0.05,0.20,1,0,-0.3\n")
    boxes = list(ACTIVE)
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({"boxes": [
        {"name": n, "center": [-0.8, -0.8 + 0.12 * k, 0.05], "half_extents": [0.05] * 3}
        for k, n in enumerate(boxes)]}))
    view = tmp_path / "view.html"
    code = main(["solve", "--robot", str(urdf), "--case", str(case), "--scene", str(scene),
                 "--home", "0,-90,90,-90,-90,0", "--seed", "0", "--limits", str(limits),
                 "--view", str(view), "--no-progress"])
    assert code == 0, capsys.readouterr().err
    raw = view.read_text(encoding="utf-8")
    page = outline(raw)
    assert not set(page.text["data"]) & {"<", ">", "&", "\u2028", "\u2029"}
    doc = json.loads(page.text["data"])
    assert doc["robot"] == robot and [b["name"] for b in doc["boxes"]] == boxes
    assert doc["title"].startswith(f"{robot}: 2 targets from {case}")
    assert page.text["head"] == shown(doc["title"])
    dom, text = _dom(view, tmp_path / "profile")
    assert _injected(dom) == []
    assert _status(text)[0] == "1"
    assert dom.text["head"] == shown(doc["title"])
