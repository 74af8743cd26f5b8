"""A 3-D view of a serial arm executing a tour: one self-contained, offline HTML file.

:func:`write_tour_html` computes, in Python with Pinocchio, the world position of
every joint origin and of the tool point at each (sub-sampled) time step, embeds
them as JSON in one HTML page together with the targets, their tool axes, the
tool path and the scene's boxes, and adds a small renderer written for this page
(HTML canvas 2-D with a perspective projection and painter's-algorithm depth
order, box faces at their farthest corner so points on a face stay visible; no
library, no CDN, no server). The page shows:

* the arm as thick segments between consecutive joint origins (base, joint 1,
  ..., joint n, tool point), whose width follows the perspective (capsules seen
  from the side), joints as dots;
* the targets (numbered by their index) and a short line along each tool axis;
* the whole tool path (grey) and the part already executed (blue);
* the boxes, shaded faces with their edges; the scene's meshes, flat-shaded triangles
  (simplified above ``max_triangles``, :mod:`subtask_opt.plotting.cell_geometry`);
* the scene's tool (its boxes and meshes, orange) on the frame it is mounted on, moving
  with the arm;
* detoured legs (planned around an obstacle, :mod:`subtask_opt.cell.detour`): their part
  of the tool path in purple, the TCP at each waypoint a purple square;
* a ground grid (0.1 m) at z = 0 and the base frame's x/y/z axes.

Controls: play/pause, a time slider, a speed menu, mouse drag to rotate, wheel
to zoom, double click to reset the view; ``page.html#t=2.5`` opens at t = 2.5 s.
The element ``#status`` reads ``rendered frame k of F frames`` (attribute
``data-ok="1"``) once the first frame is drawn, k following the animation (the slider,
play, ``#t=``), or ``error: ...`` (``data-ok="0"``) when the script fails: the tests load
the page in a headless Chromium and read it.

Text from the inputs (the title, the robot's name, box, mesh and frame names, file names)
reaches the page only as HTML-escaped text (the title and heading) or inside the JSON
document, where ``<``,
``>``, ``&`` and U+2028/2029 are ``\\u`` escapes (:func:`script_json`), so it cannot end the
``<script>`` element or become markup; the script shows strings with ``textContent`` only.

The page's size is bounded: at most ``max_frames`` frames (default 2000,
evenly spaced in the index, first and last kept) with coordinates rounded to
0.1 mm, so about 50 bytes per joint per frame (and 12 numbers per frame for a tool), plus
at most ``max_triangles`` mesh triangles.
"""

from __future__ import annotations

import html
import json
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_int
from subtask_opt.plotting.cell_geometry import (
    VIEW_TRIANGLES,
    Surface,
    checked_detours,
    frame_poses,
    scene_surfaces,
    tool_surfaces,
)

if TYPE_CHECKING:
    from subtask_opt.cell.scene import Scene
    from subtask_opt.kinematics.serial import SerialArm

MAX_FRAMES = 2000
"""Default largest number of animation frames written into one page."""

LINK_COLOUR = "#e8590c"
"""Colour of the arm's links (the browser test looks for it on the screenshot)."""

_DECIMALS = 4  # 0.1 mm


def checked_array(owner: str, name: str, value: Any,
                  shape: tuple[int | None, ...]) -> np.ndarray:
    """``value`` as a finite float array of ``shape`` (None: any size); ParameterError
    naming ``owner`` and ``name`` (the array checks of the serial-arm figures)."""
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"{owner}: {name} must be an array of numbers, "
                             f"got {type(value).__name__}") from None
    if arr.ndim != len(shape) or any(s is not None and a != s
                                     for a, s in zip(arr.shape, shape, strict=True)):
        want = "(" + ", ".join("any" if s is None else str(s) for s in shape) + (
            ",)" if len(shape) == 1 else ")")
        raise ParameterError(f"{owner}: {name} must have shape {want}, "
                             f"got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{owner}: {name} must be finite")
    return arr


def frame_indices(count: int, max_frames: int) -> np.ndarray:
    """At most ``max_frames`` indices into ``range(count)``, evenly spaced, first and last kept."""
    require_int("frame_indices", "count", count, 1)
    require_int("frame_indices", "max_frames", max_frames, 2)
    if count <= max_frames:
        return np.arange(count)
    return np.unique(np.round(np.linspace(0, count - 1, max_frames)).astype(np.int64))


def skeleton_points(arm: SerialArm, q: np.ndarray) -> np.ndarray:
    """(T, n + 2, 3) world positions: base origin, the n joint origins, the tool point.

    Computed with Pinocchio's forward kinematics (``data.oMi`` and the tool frame).
    """
    import pinocchio as pin

    model, data = arm.model, arm.data
    out = np.empty((q.shape[0], model.njoints + 1, 3))
    for k, qk in enumerate(q):
        pin.forwardKinematics(model, data, qk)
        for j in range(model.njoints):
            out[k, j] = data.oMi[j].translation
        out[k, -1] = pin.updateFramePlacement(model, data, arm.tool_frame_id).translation
    return out


def _box_corners(box: Any) -> list[list[float]]:
    """The 8 corners of a box, index bits (x, y, z) = (i & 1, i & 2, i & 4)."""
    corners = []
    for i in range(8):
        sign = np.array([1 if i & 1 else -1, 1 if i & 2 else -1, 1 if i & 4 else -1])
        corners.append(box.center + box.rotation @ (sign * box.half_extents))
    return np.round(np.array(corners), _DECIMALS).tolist()


def _rounded(arr: np.ndarray) -> Any:
    return np.round(arr, _DECIMALS).tolist()


def _surface_json(surface: Surface) -> dict[str, Any]:
    return {"name": surface.name, "vertices": _rounded(surface.vertices.reshape(-1)),
            "triangles": surface.triangles.reshape(-1).astype(int).tolist()}


def tour_view_data(arm: SerialArm, times: Any, q: Any, *, targets: Any = None, axes: Any = None,
                   scene: Scene | None = None, title: str = "", order: Any = None,
                   max_frames: int = MAX_FRAMES, detours: Any = None,
                   max_triangles: int = VIEW_TRIANGLES) -> dict[str, Any]:
    """The JSON document :func:`write_tour_html` embeds (validated; see its arguments)."""
    from subtask_opt.cell.scene import Scene
    from subtask_opt.kinematics.serial import SerialArm

    if not isinstance(arm, SerialArm):
        raise ParameterError(f"write_tour_html: arm must be a SerialArm, got {type(arm).__name__}")
    t = checked_array("write_tour_html", "times", times, (None,))
    if t.size == 0:
        raise ParameterError("write_tour_html: times must hold at least one time")
    if t.size > 1 and np.any(np.diff(t) < 0):
        bad = int(np.argmax(np.diff(t) < 0))
        raise ParameterError(f"write_tour_html: times must be non-decreasing, got "
                             f"times[{bad}]={t[bad]} > times[{bad + 1}]={t[bad + 1]}")
    qa = checked_array("write_tour_html", "q", q, (t.size, arm.nq))
    require_int("write_tour_html", "max_frames", max_frames, 2)
    if not isinstance(title, str):
        raise ParameterError(f"write_tour_html: title must be a string, got {title!r}")
    if scene is not None and not isinstance(scene, Scene):
        raise ParameterError(f"write_tour_html: scene must be a Scene or None, "
                             f"got {type(scene).__name__}")
    pts = (np.zeros((0, 3)) if targets is None
           else checked_array("write_tour_html", "targets", targets, (None, 3)))
    if axes is not None:
        if targets is None:
            raise ParameterError("write_tour_html: axes need targets")
        ax = checked_array("write_tour_html", "axes", axes, (pts.shape[0], 3))
        norms = np.linalg.norm(ax, axis=1)
        if np.any(norms < 1e-12):
            raise ParameterError(f"write_tour_html: axes[{int(np.argmin(norms))}] is zero; "
                                 "each axis must be a non-zero 3-vector")
        ax = ax / norms[:, None]
    else:
        ax = np.zeros((0, 3))
    labels = [str(i) for i in range(pts.shape[0])]
    if order is not None:
        o = np.asarray(order)
        n = pts.shape[0]
        if o.shape != (n,) or not np.issubdtype(o.dtype, np.integer) or \
                not np.array_equal(np.sort(o), np.arange(n)):
            raise ParameterError(f"write_tour_html: order must be a permutation of the "
                                 f"{n} target indices, got {order!r}")
        for visit, i in enumerate(o):
            labels[int(i)] = str(visit + 1)
    require_int("write_tour_html", "max_triangles", max_triangles, 12)
    legs = checked_detours("write_tour_html", detours, arm.nq)
    idx = frame_indices(t.size, max_frames)
    skel = skeleton_points(arm, qa[idx])
    boxes = [] if scene is None else [{"name": b.name, "corners": _box_corners(b)}
                                      for b in scene.boxes]
    meshes = [_surface_json(s) for s in scene_surfaces(scene, max_triangles)]
    tool: dict[str, Any] | None = None
    if scene is not None and scene.tool is not None and scene.tool.has_geometry:
        poses = frame_poses(arm, qa[idx], scene.tool.frame)
        tool = {"frame": scene.tool.frame,
                "parts": [_surface_json(s) for s in tool_surfaces(scene, max_triangles)],
                # per frame: the mounting frame's rotation (row-major) and origin
                "poses": np.round(np.concatenate([poses[:, :3, :3].reshape(-1, 9),
                                                  poses[:, :3, 3]], axis=1), 5).tolist()}
    detoured = [{"t": [round(leg.start, 6), round(leg.end, 6)],
                 "corners": _rounded(np.array([arm.fk(w)[:3, 3] for w in leg.waypoints]))}
                for leg in legs]
    return {
        "title": title or f"{arm.name}: tour of {pts.shape[0]} targets",
        "robot": arm.name,
        "t": np.round(t[idx], 6).tolist(),
        "frames": _rounded(skel.reshape(len(idx), -1)),
        "n_points": int(skel.shape[1]),
        "targets": _rounded(pts),
        "labels": labels,
        "label_kind": "index" if order is None else "visit number",
        "axes": _rounded(ax),
        "boxes": boxes,
        "meshes": meshes,
        "tool": tool,
        "detours": detoured,
        "source_frames": int(t.size),
    }


def write_tour_html(path: str | Path, arm: SerialArm, times: Any, q: Any, *,
                    targets: Any = None, axes: Any = None, scene: Scene | None = None,
                    title: str = "", order: Any = None, max_frames: int = MAX_FRAMES,
                    detours: Any = None, max_triangles: int = VIEW_TRIANGLES) -> Path:
    """Write an offline HTML animation of ``arm`` moving through ``q`` at ``times``.

    Args:
        path: the HTML file to write (parent folders are created).
        arm: the arm (:func:`~subtask_opt.kinematics.serial.load_serial_arm`).
        times: (T,) non-decreasing times (s).
        q: (T, nq) joint positions (rad, m) at those times.
        targets: optional (N, 3) target positions (m, base frame), drawn numbered:
            by index, or by visit (1 = first) when ``order`` is given.
        axes: optional (N, 3) tool axes at the targets (drawn as short lines).
        scene: optional :class:`~subtask_opt.cell.scene.Scene`: its boxes and meshes are
            drawn, and its tool's parts on the frame they are mounted on, moving with the arm.
        title: the page's heading (default: robot and target count).
        order: optional (N,) target indices in visiting order (labels the targets).
        max_frames: most frames embedded (sub-sampled evenly, first and last kept).
        detours: optional detoured legs
            (:func:`~subtask_opt.plotting.cell_geometry.detour_legs` of the trajectory):
            their part of the tool path is drawn in purple, the TCP at their waypoints
            as purple squares.
        max_triangles: most mesh triangles drawn, all meshes together (a larger mesh is
            simplified for the picture, :mod:`subtask_opt.plotting.cell_geometry`).

    Returns:
        The path written.

    Raises:
        ParameterError: a shape, a non-finite value, decreasing times, zero axes.
    """
    data = tour_view_data(arm, times, q, targets=targets, axes=axes, scene=scene, title=title,
                          order=order, max_frames=max_frames, detours=detours,
                          max_triangles=max_triangles)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(render_page(data), encoding="utf-8")
    return out


_SCRIPT_SAFE = str.maketrans({"<": "\\u003c", ">": "\\u003e", "&": "\\u0026",
                              "\u2028": "\\u2028", "\u2029": "\\u2029"})
_PLACEHOLDER = re.compile(r"@(TITLE|LINK_COLOUR|DATA)@")
_SURROGATE = re.compile("[\ud800-\udfff]")


def script_json(data: Any) -> str:
    """``data`` as JSON that is inert inside a ``<script>`` element.

    ``<``, ``>`` and ``&`` can only occur inside JSON strings (or keys), where ``\\u003c``
    etc. mean the same characters to ``JSON.parse``; without them no ``</script>``,
    ``<!--`` or ``<script`` can end the element or change how the HTML parser reads it.
    U+2028/2029 are escaped too (line terminators in older JavaScript), and non-ASCII text
    (lone surrogates included) travels as ``\\u`` escapes.
    """
    return json.dumps(data, separators=(",", ":"), allow_nan=False,
                      ensure_ascii=True).translate(_SCRIPT_SAFE)


def html_text(text: str) -> str:
    """``text`` escaped for HTML text and attribute values; a lone surrogate (a file name
    that was not UTF-8) becomes U+FFFD so that the page can be written as UTF-8."""
    return html.escape(_SURROGATE.sub("\ufffd", text), quote=True)


def render_page(data: dict[str, Any]) -> str:
    """The HTML page for a :func:`tour_view_data` document.

    The only text from the inputs in the page is the HTML-escaped title (``<title>`` and the
    heading) and the JSON document (:func:`script_json`); the placeholders are filled in one
    pass, so a title or a name that spells a placeholder stays text. The page's script puts
    strings into the document with ``textContent`` (canvas labels with ``fillText``), never as
    markup.
    """
    values = {"TITLE": html_text(data["title"]), "LINK_COLOUR": LINK_COLOUR,
              "DATA": script_json(data)}
    return _PLACEHOLDER.sub(lambda m: values[m.group(1)], _PAGE)


_PAGE = r"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>@TITLE@</title>
<style>
  html, body { margin: 0; height: 100%; font-family: sans-serif; background: #ffffff; }
  #wrap { display: flex; flex-direction: column; height: 100%; }
  #head { padding: 6px 12px; font-size: 15px; font-weight: bold; color: #222; }
  #view { flex: 1; position: relative; min-height: 200px; }
  #canvas { width: 100%; height: 100%; display: block; cursor: grab; }
  #legend { position: absolute; top: 8px; right: 12px; background: rgba(255,255,255,0.88);
            border: 1px solid #bbb; padding: 6px 10px; font-size: 12px; line-height: 1.6; }
  #legend span.sw { display: inline-block; width: 22px; height: 4px; margin-right: 6px;
                    vertical-align: middle; }
  #legend span.dot { background: #2b8a3e; height: 8px; width: 8px; border-radius: 4px; }
  #help { position: absolute; bottom: 6px; left: 12px; font-size: 11px; color: #666; }
  #controls { padding: 6px 12px; display: flex; gap: 10px; align-items: center;
              border-top: 1px solid #ddd; font-size: 13px; }
  #slider { flex: 1; }
  #status { font-size: 11px; color: #666; min-width: 160px; }
</style>
</head>
<body>
<div id="wrap">
  <div id="head">@TITLE@</div>
  <div id="view">
    <canvas id="canvas"></canvas>
    <div id="legend">
      <div><span class="sw" style="background:@LINK_COLOUR@;height:6px"></span>
        arm links (joint origins)</div>
      <div><span class="sw" style="background:#1c7ed6"></span>tool path, executed</div>
      <div><span class="sw" style="background:#adb5bd"></span>tool path, to come</div>
      <div><span class="sw dot"></span>targets (<span id="label-kind">index</span>) and
        tool axes</div>
      <div id="legend-boxes"><span class="sw"
        style="background:rgba(120,120,160,0.5);height:10px"></span>
        scene boxes</div>
      <div id="legend-meshes"><span class="sw"
        style="background:rgba(150,160,120,0.6);height:10px"></span>
        scene meshes</div>
      <div id="legend-tool"><span class="sw" style="background:#f59f00;height:10px"></span>
        tool (on <span id="tool-frame"></span>)</div>
      <div id="legend-detours"><span class="sw" style="background:#9c36b5"></span>
        detoured legs (squares: waypoints)</div>
      <div id="scale"></div>
    </div>
    <div id="help">drag: rotate &middot; wheel: zoom &middot; double click: reset view</div>
  </div>
  <div id="controls">
    <button id="play" type="button">play</button>
    <input id="slider" type="range" min="0" max="0" value="0" step="1">
    <span id="clock">t = 0.000 s</span>
    <label>speed <select id="speed">
      <option value="0.25">0.25x</option><option value="0.5">0.5x</option>
      <option value="1" selected>1x</option><option value="2">2x</option>
      <option value="4">4x</option></select></label>
    <span id="status" data-ok="">loading</span>
  </div>
</div>
<script type="application/json" id="tour-data">@DATA@</script>
<script>
"use strict";
(function () {
  var statusEl = document.getElementById("status");
  function fail(msg) {
    statusEl.textContent = "error: " + msg;
    statusEl.setAttribute("data-ok", "0");
  }
  window.addEventListener("error", function (ev) { fail(ev.message); });
  try {
    var D = JSON.parse(document.getElementById("tour-data").textContent);
    var T = D.t.length, P = D.n_points;
    if (!(T >= 1) || D.frames.length !== T || D.frames[0].length !== 3 * P ||
        D.labels.length !== D.targets.length) {
      throw new Error("malformed tour data");
    }
    var LINK = "@LINK_COLOUR@";
    document.getElementById("label-kind").textContent = D.label_kind;
    var canvas = document.getElementById("canvas");
    var ctx = canvas.getContext("2d");
    var slider = document.getElementById("slider");
    var clock = document.getElementById("clock");
    var playBtn = document.getElementById("play");
    var speedSel = document.getElementById("speed");
    slider.max = String(T - 1);
    var MESHES = D.meshes || [], TOOL = D.tool || null, DETOURS = D.detours || [];
    if (TOOL && TOOL.poses.length !== T) throw new Error("malformed tour data");
    if (!D.boxes.length) document.getElementById("legend-boxes").style.display = "none";
    if (!MESHES.length) document.getElementById("legend-meshes").style.display = "none";
    if (TOOL) document.getElementById("tool-frame").textContent = TOOL.frame;
    else document.getElementById("legend-tool").style.display = "none";
    if (!DETOURS.length) document.getElementById("legend-detours").style.display = "none";
    // frame k's path segment (k - 1 -> k) belongs to a detoured leg
    var inDetour = [];
    for (var k0 = 0; k0 < T; k0++) {
      inDetour.push(k0 > 0 && DETOURS.some(function (dl) {
        return D.t[k0 - 1] >= dl.t[0] - 1e-9 && D.t[k0] <= dl.t[1] + 1e-9;
      }));
    }

    function pt(frame, j) {
      var f = D.frames[frame];
      return [f[3 * j], f[3 * j + 1], f[3 * j + 2]];
    }
    // scene bounds -> camera target and distance
    var lo = [Infinity, Infinity, 0], hi = [-Infinity, -Infinity, 0];
    function grow(p) {
      for (var i = 0; i < 3; i++) { lo[i] = Math.min(lo[i], p[i]); hi[i] = Math.max(hi[i], p[i]); }
    }
    for (var k = 0; k < T; k++) for (var j = 0; j < P; j++) grow(pt(k, j));
    D.targets.forEach(grow);
    D.boxes.forEach(function (b) { b.corners.forEach(grow); });
    function vertex(m, i) {
      return [m.vertices[3 * i], m.vertices[3 * i + 1], m.vertices[3 * i + 2]];
    }
    MESHES.forEach(function (m) {
      for (var i = 0; 3 * i < m.vertices.length; i++) grow(vertex(m, i));
    });
    var toolReach = 0;  // the tool lies within this distance of its frame's origin
    if (TOOL) {
      TOOL.parts.forEach(function (m) {
        for (var i = 0; 3 * i < m.vertices.length; i++) {
          toolReach = Math.max(toolReach, Math.hypot.apply(null, vertex(m, i)));
        }
      });
      TOOL.poses.forEach(function (ps) {
        grow([ps[9] - toolReach, ps[10] - toolReach, ps[11] - toolReach]);
        grow([ps[9] + toolReach, ps[10] + toolReach, ps[11] + toolReach]);
      });
    }
    var center = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2];
    var radius = Math.max(0.05, 0.5 * Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]));
    var extent = Math.max(hi[0] - lo[0], hi[1] - lo[1], 0.2);
    var gstep = extent <= 2 ? 0.1 : Math.pow(10, Math.floor(Math.log10(extent))) / 10;
    document.getElementById("scale").textContent = "ground grid " + gstep + " m (z = 0)";
    // start looking from the side, a little from the robot's side of the targets
    var az0 = -0.9;
    if (D.targets.length) {
      var cx = 0, cy = 0;
      D.targets.forEach(function (p) { cx += p[0]; cy += p[1]; });
      if (Math.hypot(cx, cy) > 1e-9) az0 = Math.atan2(cy, cx) - 1.9;
    }
    var home = { az: az0, el: 0.45, dist: 2.6 * radius };
    var cam = { az: home.az, el: home.el, dist: home.dist };
    var W = 0, H = 0, F = 1, eye, R, U, Fw;

    function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
    function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
    function cross(a, b) {
      return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    }
    function norm(a) { var n = Math.sqrt(dot(a, a)) || 1; return [a[0] / n, a[1] / n, a[2] / n]; }
    function setCamera() {
      var ce = Math.cos(cam.el);
      eye = [center[0] + cam.dist * ce * Math.cos(cam.az),
             center[1] + cam.dist * ce * Math.sin(cam.az),
             center[2] + cam.dist * Math.sin(cam.el)];
      Fw = norm(sub(center, eye));
      R = norm(cross(Fw, [0, 0, 1]));
      U = cross(R, Fw);
      F = 0.5 * Math.min(W, H) / Math.tan(0.35);
    }
    // world point -> [sx, sy, depth] (null behind the camera)
    function proj(p) {
      var d = sub(p, eye), z = dot(d, Fw);
      if (z < 1e-3) return null;
      return [W / 2 + F * dot(d, R) / z, H / 2 - F * dot(d, U) / z, z];
    }
    function resize() {
      var r = canvas.getBoundingClientRect(), s = window.devicePixelRatio || 1;
      W = Math.max(r.width, 10); H = Math.max(r.height, 10);
      canvas.width = Math.round(W * s); canvas.height = Math.round(H * s);
      ctx.setTransform(s, 0, 0, s, 0, 0);
    }
    function line(a, b, colour, width) {
      ctx.strokeStyle = colour; ctx.lineWidth = width; ctx.lineCap = "round";
      ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
    }
    function disc(a, r, colour) {
      ctx.fillStyle = colour; ctx.beginPath(); ctx.arc(a[0], a[1], r, 0, 2 * Math.PI); ctx.fill();
    }
    var FACES = [[0, 1, 3, 2], [4, 5, 7, 6], [0, 1, 5, 4], [2, 3, 7, 6], [0, 2, 6, 4],
                 [1, 3, 7, 5]];
    var LIGHT = norm([0.4, -0.5, 1.0]);
    var frame = 0, playing = false, tNow = D.t[0], last = null;
    // one triangle of a surface, flat-shaded, painted at its farthest corner's depth (as
    // the box faces: targets drawn on a part stay visible)
    function triangle(items, w, s, rgb, alpha) {
      if (!s[0] || !s[1] || !s[2]) return;
      var n = norm(cross(sub(w[1], w[0]), sub(w[2], w[0])));
      var shade = 0.55 + 0.45 * Math.abs(dot(n, LIGHT));
      var fill = "rgba(" + Math.round(rgb[0] * shade) + "," + Math.round(rgb[1] * shade) + "," +
                 Math.round(rgb[2] * shade) + "," + alpha + ")";
      items.push({ d: Math.max(s[0][2], s[1][2], s[2][2]), f: function () {
        ctx.fillStyle = fill; ctx.strokeStyle = fill; ctx.lineWidth = 0.5;
        ctx.beginPath(); ctx.moveTo(s[0][0], s[0][1]); ctx.lineTo(s[1][0], s[1][1]);
        ctx.lineTo(s[2][0], s[2][1]); ctx.closePath(); ctx.fill(); ctx.stroke();
      } });
    }
    function surface(items, m, place, rgb, alpha) {
      var w = [], s = [];
      for (var i = 0; 3 * i < m.vertices.length; i++) {
        var p = place(vertex(m, i));
        w.push(p); s.push(proj(p));
      }
      for (var k = 0; k < m.triangles.length; k += 3) {
        var a = m.triangles[k], b = m.triangles[k + 1], c = m.triangles[k + 2];
        triangle(items, [w[a], w[b], w[c]], [s[a], s[b], s[c]], rgb, alpha);
      }
    }
    function same(p) { return p; }
    function square(a, r, colour) {
      ctx.fillStyle = colour; ctx.fillRect(a[0] - r, a[1] - r, 2 * r, 2 * r);
    }

    function draw() {
      setCamera();
      ctx.clearRect(0, 0, W, H);
      ctx.fillStyle = "#ffffff"; ctx.fillRect(0, 0, W, H);
      // ground grid and base axes (always behind the rest)
      var g0x = Math.floor(lo[0] / gstep - 2) * gstep, g1x = Math.ceil(hi[0] / gstep + 2) * gstep;
      var g0y = Math.floor(lo[1] / gstep - 2) * gstep, g1y = Math.ceil(hi[1] / gstep + 2) * gstep;
      for (var x = g0x; x <= g1x + 1e-9; x += gstep) {
        var a = proj([x, g0y, 0]), b = proj([x, g1y, 0]);
        if (a && b) line(a, b, "#e9ecef", 1);
      }
      for (var y = g0y; y <= g1y + 1e-9; y += gstep) {
        var a2 = proj([g0x, y, 0]), b2 = proj([g1x, y, 0]);
        if (a2 && b2) line(a2, b2, "#e9ecef", 1);
      }
      var o = proj([0, 0, 0]), axl = 2 * gstep;
      var AXES = [[[axl, 0, 0], "#c92a2a", "x"], [[0, axl, 0], "#2f9e44", "y"],
                  [[0, 0, axl], "#1864ab", "z"]];
      AXES.forEach(function (a3) {
        var e = proj(a3[0]);
        if (!o || !e) return;
        line(o, e, a3[1], 2);
        ctx.fillStyle = a3[1]; ctx.font = "12px sans-serif";
        ctx.fillText(a3[2], e[0] + 3, e[1] - 3);
      });
      var items = [];  // {d: depth, f: painter}
      D.boxes.forEach(function (b) {
        var c = b.corners.map(proj);
        FACES.forEach(function (fc) {
          var pts = fc.map(function (i) { return c[i]; });
          if (pts.some(function (p) { return p === null; })) return;
          var w = fc.map(function (i) { return b.corners[i]; });
          var n = norm(cross(sub(w[1], w[0]), sub(w[3], w[0])));
          var shade = 0.55 + 0.35 * Math.abs(dot(n, LIGHT));
          // a face is painted at its farthest corner's depth: what lies on it or in
          // front of any part of it (holes on a panel) is drawn over the translucent face
          var depth = Math.max(pts[0][2], pts[1][2], pts[2][2], pts[3][2]);
          items.push({ d: depth, f: function () {
            var grey = Math.round(120 * shade + 40), blue = Math.round(160 * shade + 40);
            ctx.fillStyle = "rgba(" + grey + "," + grey + "," + blue + ",0.55)";
            ctx.strokeStyle = "#495057"; ctx.lineWidth = 1;
            ctx.beginPath(); ctx.moveTo(pts[0][0], pts[0][1]);
            for (var i = 1; i < 4; i++) ctx.lineTo(pts[i][0], pts[i][1]);
            ctx.closePath(); ctx.fill(); ctx.stroke();
          } });
        });
      });
      MESHES.forEach(function (m) { surface(items, m, same, [170, 180, 135], 0.5); });
      if (TOOL) {
        var ps = TOOL.poses[frame];
        var mount = function (v) {
          return [ps[0] * v[0] + ps[1] * v[1] + ps[2] * v[2] + ps[9],
                  ps[3] * v[0] + ps[4] * v[1] + ps[5] * v[2] + ps[10],
                  ps[6] * v[0] + ps[7] * v[1] + ps[8] * v[2] + ps[11]];
        };
        TOOL.parts.forEach(function (m) { surface(items, m, mount, [245, 159, 0], 0.9); });
      }
      // tool path: executed (blue) and to come (grey); detoured legs purple
      for (var k = 1; k < T; k++) {
        var p0 = proj(pt(k - 1, P - 1)), p1 = proj(pt(k, P - 1));
        if (!p0 || !p1) continue;
        (function (p0, p1, done, det) {
          var colour = det ? (done ? "#9c36b5" : "#d0a3e0") : (done ? "#1c7ed6" : "#adb5bd");
          items.push({ d: (p0[2] + p1[2]) / 2, f: function () {
            line(p0, p1, colour, done ? 2.5 : (det ? 2 : 1.5));
          } });
        })(p0, p1, k <= frame, inDetour[k]);
      }
      DETOURS.forEach(function (dl) {
        dl.corners.slice(1, -1).forEach(function (c) {
          var a = proj(c);
          if (a) items.push({ d: a[2], f: function () { square(a, 3.5, "#9c36b5"); } });
        });
      });
      D.targets.forEach(function (tp, i) {
        var a = proj(tp);
        if (!a) return;
        var ax = D.axes.length ? D.axes[i] : null;
        var L = 0.05;
        var e = ax ? proj([tp[0] + L * ax[0], tp[1] + L * ax[1], tp[2] + L * ax[2]]) : null;
        items.push({ d: a[2], f: function () {
          if (e) line(a, e, "#2b8a3e", 1.5);
          disc(a, 4, "#2b8a3e");
          ctx.fillStyle = "#1b4332"; ctx.font = "11px sans-serif";
          ctx.fillText(D.labels[i], a[0] + 5, a[1] - 5);
        } });
      });
      // the arm: thick segments (capsules), joints as dots
      var sp = [];
      for (var j = 0; j < P; j++) sp.push(proj(pt(frame, j)));
      for (var j2 = 1; j2 < P; j2++) {
        var s0 = sp[j2 - 1], s1 = sp[j2];
        if (!s0 || !s1) continue;
        (function (s0, s1, last) {
          var d = (s0[2] + s1[2]) / 2, wpx = Math.max(3, F * (last ? 0.025 : 0.045) / d);
          items.push({ d: d - 1e-4, f: function () {
            line(s0, s1, "#7f2704", wpx + 2); line(s0, s1, LINK, wpx);
          } });
        })(s0, s1, j2 === P - 1);
      }
      sp.forEach(function (s, j) {
        if (!s) return;
        var r = Math.max(2.5, F * 0.03 / s[2]);
        items.push({ d: s[2] - 2e-4, f: function () {
          disc(s, r, j === P - 1 ? "#1c7ed6" : "#343a40");
        } });
      });
      items.sort(function (a, b) { return b.d - a.d; });
      items.forEach(function (it) { it.f(); });
      clock.textContent = "t = " + D.t[frame].toFixed(3) + " s / " + D.t[T - 1].toFixed(3) + " s";
      slider.value = String(frame);
      // the status line follows the animation (an error, once shown, stays)
      if (statusEl.getAttribute("data-ok") !== "0") {
        statusEl.textContent = "rendered frame " + frame + " of " + T + " frames";
      }
    }
    function frameAt(t) {  // last frame whose time <= t
      var a = 0, b = T - 1;
      while (a < b) { var m = (a + b + 1) >> 1; if (D.t[m] <= t) a = m; else b = m - 1; }
      return a;
    }
    function tick(now) {
      if (!playing) { last = null; return; }
      if (last !== null) tNow += (now - last) / 1000 * parseFloat(speedSel.value);
      last = now;
      if (tNow >= D.t[T - 1]) { tNow = D.t[T - 1]; playing = false; playBtn.textContent = "play"; }
      frame = frameAt(tNow);
      draw();
      if (playing) window.requestAnimationFrame(tick);
    }
    playBtn.addEventListener("click", function () {
      playing = !playing;
      playBtn.textContent = playing ? "pause" : "play";
      if (playing) {
        if (frame >= T - 1) { frame = 0; tNow = D.t[0]; }
        last = null; window.requestAnimationFrame(tick);
      }
    });
    slider.addEventListener("input", function () {
      frame = parseInt(slider.value, 10); tNow = D.t[frame]; draw();
    });
    var drag = null;
    canvas.addEventListener("mousedown", function (e) {
      drag = [e.clientX, e.clientY]; canvas.style.cursor = "grabbing";
    });
    window.addEventListener("mouseup", function () { drag = null; canvas.style.cursor = "grab"; });
    window.addEventListener("mousemove", function (e) {
      if (!drag) return;
      cam.az -= (e.clientX - drag[0]) * 0.01;
      cam.el = Math.max(-1.5, Math.min(1.5, cam.el + (e.clientY - drag[1]) * 0.01));
      drag = [e.clientX, e.clientY]; draw();
    });
    canvas.addEventListener("wheel", function (e) {
      e.preventDefault();
      var d = cam.dist * Math.exp(e.deltaY * 0.001);
      cam.dist = Math.max(0.05 * radius, Math.min(20 * radius, d));
      draw();
    }, { passive: false });
    canvas.addEventListener("dblclick", function () {
      cam.az = home.az; cam.el = home.el; cam.dist = home.dist; draw();
    });
    window.addEventListener("resize", function () { resize(); draw(); });
    resize();
    draw();
    var m = /^#t=([0-9.]+)$/.exec(window.location.hash);  // open at a time: page.html#t=2.5
    if (m) { tNow = parseFloat(m[1]); frame = frameAt(tNow); draw(); }
    statusEl.setAttribute("data-ok", "1");
  } catch (err) {
    fail(err && err.message ? err.message : String(err));
  }
})();
</script>
</body>
</html>
"""
