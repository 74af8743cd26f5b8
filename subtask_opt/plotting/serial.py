"""Figure of a serial-arm tour: targets and tool path in 3-D, the targets in their plane, and
the time of every leg."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.base.errors import ParameterError
from subtask_opt.plotting.arm3d import checked_array
from subtask_opt.plotting.cell_geometry import (
    checked_detours,
    frame_poses,
    scene_surfaces,
    tool_surfaces,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from subtask_opt.cell.scene import Scene
    from subtask_opt.kinematics.serial import SerialArm

MAX_NUMBERED = 60
"""Above this many targets only every k-th visit is numbered in the plane view."""

MAX_NUMBERED_3D = 20
"""Above this many targets the 3-D view carries no numbers (the plane view does)."""

FIGURE_TRIANGLES = 6000
"""Most mesh triangles the figure draws (matplotlib sorts and draws every one)."""

DETOUR_COLOUR = "#9c36b5"

_BOX_EDGES = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7),
              (0, 4), (1, 5), (2, 6), (3, 7)]


def target_plane(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Best-fit plane of (N, 3) points: (centroid, unit u, unit v, largest distance off it).

    The plane's normal is the points' least principal direction. Its in-plane axes
    follow the base frame so the picture reads naturally: v is "up" (the base z axis
    projected on the plane) unless the plane is nearly horizontal, where u and v
    follow the projected x axis; each axis is signed so its largest component is
    positive.
    """
    origin = points.mean(axis=0)
    centred = points - origin
    normal = np.linalg.svd(centred, full_matrices=True)[2][2]

    def along(w: np.ndarray) -> np.ndarray:
        e = w - (w @ normal) * normal
        e = e / np.linalg.norm(e)
        return e if e[int(np.argmax(np.abs(e)))] > 0 else -e

    if abs(float(normal[2])) < 0.9:
        v = along(np.array([0.0, 0.0, 1.0]))
        u = along(np.cross(v, normal))
    else:
        u = along(np.array([1.0, 0.0, 0.0]))
        v = along(np.cross(normal, u))
    off = float(np.abs(centred @ normal).max())
    return origin, u, v, off


def serial_tour_figure(arm: SerialArm, targets: Any, tool_path: Any, leg_times: Any,
                       order: Any, *, title: str = "", q_home: Any = None,
                       scene: Scene | None = None, detours: Any = None) -> Figure:
    """The figure of :func:`plot_serial_tour`, not saved (arguments as there)."""
    import matplotlib.pyplot as plt

    pts = checked_array("plot_serial_tour", "targets", targets, (None, 3))
    n = pts.shape[0]
    if n == 0:
        raise ParameterError("plot_serial_tour: targets must hold at least one target")
    path = checked_array("plot_serial_tour", "tool_path", tool_path, (None, 3))
    if path.shape[0] < 2:
        raise ParameterError(f"plot_serial_tour: tool_path needs at least 2 points, "
                             f"got {path.shape[0]}")
    raw = np.asarray(leg_times)
    # N + 1 legs: a closed tour back home; N: an open path ending at its last target
    legs = checked_array("plot_serial_tour", "leg_times", leg_times,
                         (n,) if raw.shape == (n,) else (n + 1,))
    closed = legs.shape[0] == n + 1
    if np.any(legs < 0):
        raise ParameterError(f"plot_serial_tour: leg_times must be >= 0, got min "
                             f"{legs.min()}")
    o = np.asarray(order)
    if o.shape != (n,) or not np.issubdtype(o.dtype, np.integer) or \
            not np.array_equal(np.sort(o), np.arange(n)):
        raise ParameterError(f"plot_serial_tour: order must be a permutation of 0..{n - 1}, "
                             f"got {order!r}")
    if not isinstance(title, str):
        raise ParameterError(f"plot_serial_tour: title must be a string, got {title!r}")
    detoured = checked_detours("plot_serial_tour", detours, arm.nq)
    for k, leg in enumerate(detoured):
        if not 0 <= leg.index < legs.shape[0]:
            raise ParameterError(f"plot_serial_tour: detours[{k}].index must be a leg "
                                 f"number in [0, {legs.shape[0] - 1}], got {leg.index}")

    fig = plt.figure(figsize=(13, 11))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.15, 1.0], height_ratios=[1.2, 1.0],
                            wspace=0.2, hspace=0.3)
    ax = fig.add_subplot(grid[0, 0], projection="3d")
    flat = fig.add_subplot(grid[0, 1])
    bar = fig.add_subplot(grid[1, :])

    # 3-D: scene, tool path, targets numbered by visit, the arm at home
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    drawn = [np.zeros((0, 3))]  # every point drawn: the axes contain them all
    for k, surf in enumerate(scene_surfaces(scene, FIGURE_TRIANGLES)):
        ax.add_collection3d(Poly3DCollection(
            surf.vertices[surf.triangles], facecolor="#a9b388", edgecolor="none", alpha=0.45,
            label="scene meshes" if k == 0 else None))
        drawn.append(surf.vertices)
    if scene is not None:
        for k, box in enumerate(scene.boxes):
            corners = np.array([box.center + box.rotation @ (np.array(
                [1 if i & 1 else -1, 1 if i & 2 else -1, 1 if i & 4 else -1]) * box.half_extents)
                for i in range(8)])
            for a, b in _BOX_EDGES:
                ax.plot(*corners[[a, b]].T, color="#868e96", lw=0.8,
                        label="scene boxes" if k == 0 and (a, b) == (0, 1) else None)
            drawn.append(corners)
    ax.plot(*path.T, color="#1c7ed6", lw=1.0, label="tool path")
    for k, leg in enumerate(detoured):  # the TCP along the straight joint segments
        tcp = np.array([arm.fk(row)[:3, 3] for row in leg.joint_path()])
        corners = np.array([arm.fk(row)[:3, 3] for row in leg.waypoints[1:-1]])
        ax.plot(*tcp.T, color=DETOUR_COLOUR, lw=1.8,
                label=f"detoured legs ({len(detoured)}; squares: waypoints)" if k == 0
                else None)
        ax.scatter(*corners.T, marker="s", s=16, color=DETOUR_COLOUR, depthshade=False)
        drawn.append(tcp)
    ax.scatter(*pts.T, color="#2b8a3e", s=18, depthshade=False, label=f"targets ({n})")
    step = max(1, int(np.ceil(n / MAX_NUMBERED)))
    if n <= MAX_NUMBERED_3D:
        for visit, i in enumerate(o):
            ax.text(*pts[i], f" {visit + 1}", fontsize=7, color="#1b4332")
    ax.scatter(*path[0], marker="*", s=140, color="#c92a2a", depthshade=False,
               label="tool at home (start and end)" if closed else "tool at home (start)")
    if q_home is not None:
        from subtask_opt.plotting.arm3d import skeleton_points

        q = checked_array("plot_serial_tour", "q_home", q_home, (arm.nq,))
        skel = skeleton_points(arm, q[None])[0]
        ax.plot(*skel.T, color="#e8590c", lw=4, solid_capstyle="round", label="arm at home")
        drawn.append(skel)
        if scene is not None and scene.tool is not None:
            mount = frame_poses(arm, q[None], scene.tool.frame)[0]
            for k, surf in enumerate(tool_surfaces(scene, FIGURE_TRIANGLES)):
                placed = surf.vertices @ mount[:3, :3].T + mount[:3, 3]
                ax.add_collection3d(Poly3DCollection(
                    placed[surf.triangles], facecolor="#f59f00", edgecolor="#a35f00",
                    linewidths=0.3, alpha=0.9,
                    label=f"tool on {scene.tool.frame}" if k == 0 else None))
                drawn.append(placed)
    every = np.vstack([pts, path, *drawn])
    lo, hi = every.min(axis=0), every.max(axis=0)
    # equal axes (a cube) that contain the scene, the arm and the path
    mid, half = (lo + hi) / 2, max(float((hi - lo).max()) / 2, 0.05)
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title("targets and tool path" + (" (numbers: visit order)" if n <= MAX_NUMBERED_3D
                                             else ""), fontsize=10)
    ax.legend(loc="upper left", bbox_to_anchor=(-0.16, 1.0), fontsize=8, framealpha=0.85)

    # the targets in their best-fit plane, joined in visiting order
    origin, e1, e2, off = target_plane(pts)
    uv = (pts - origin) @ np.column_stack([e1, e2])
    flat.plot(*uv[o].T, "-", color="#1c7ed6", lw=1.0, label="visiting order")
    flat.scatter(uv[:, 0], uv[:, 1], color="#2b8a3e", s=16, zorder=3, label="targets")
    flat.scatter(uv[o[0], 0], uv[o[0], 1], s=90, facecolor="none", edgecolor="#c92a2a",
                 lw=1.5, zorder=4, label="first target")
    for visit, i in enumerate(o):
        if visit % step == 0 or visit == n - 1:
            flat.annotate(str(visit + 1), uv[i], textcoords="offset points", xytext=(3, 3),
                          fontsize=7, color="#1b4332")
    flat.set_aspect("equal", adjustable="datalim")
    e1, e2 = np.round(e1, 2) + 0.0, np.round(e2, 2) + 0.0  # no "-0.00" in the labels
    flat.set_xlabel(f"u [m], along ({e1[0]:.2f}, {e1[1]:.2f}, {e1[2]:.2f}) in the base frame")
    flat.set_ylabel(f"v [m], along ({e2[0]:.2f}, {e2[1]:.2f}, {e2[2]:.2f})")
    numbered = "numbers: visit order" + ("" if step == 1 else f", every {step}th")
    flat.set_title(f"targets in their best-fit plane, farthest {1000 * off:.1f} mm off it\n"
                   f"({numbered})", fontsize=10)
    flat.legend(loc="best", fontsize=8, framealpha=0.85)
    flat.grid(alpha=0.3)

    # per-leg times
    x = np.arange(legs.shape[0])
    colours = np.full(legs.shape[0], "#1c7ed6", dtype=object)
    colours[[leg.index for leg in detoured]] = DETOUR_COLOUR
    bars = bar.bar(x, legs, color=list(colours), width=0.8 if n < 100 else 1.0)
    bars.set_label("leg time" + (", detoured legs purple" if detoured else ""))
    bar.axhline(legs.mean(), color="#c92a2a", lw=1, ls="--",
                label=f"mean {legs.mean():.3f} s")
    if n <= 20:
        names = ["home"] + [f"t{i}" for i in o] + (["home"] if closed else [])
        bar.set_xticks(x, [f"{names[k]}\u2192{names[k + 1]}" for k in x], rotation=60,
                       fontsize=8, ha="right")
        bar.set_xlabel("leg (from target \u2192 to target, t = target index)")
    else:
        bar.set_xlabel("leg number (0: home to first target, last: "
                       + ("back home)" if closed else "to the last target)"))
    bar.set_ylabel("leg time [s]")
    bar.set_title(f"time per leg: {legs.shape[0]} legs, total {legs.sum():.3f} s", fontsize=10)
    bar.legend(loc="upper right", fontsize=8)
    bar.grid(axis="y", alpha=0.3)
    fig.suptitle(title or f"{arm.name}: tour of {n} targets", fontsize=12)
    return fig


def plot_serial_tour(arm: SerialArm, targets: Any, tool_path: Any, leg_times: Any, order: Any,
                     path: str | Path, *, title: str = "", q_home: Any = None,
                     scene: Scene | None = None, detours: Any = None) -> Path:
    """Write a figure of a serial-arm tour: a 3-D view and a bar chart of the leg times.

    Args:
        arm: the arm (its name titles the figure; ``q_home`` is drawn with it).
        targets: (N, 3) target positions (m), numbered on the figure by visit order.
        tool_path: (T, 3) tool positions along the executed tour (m); the first is
            the tool at home.
        leg_times: (N + 1,) times (s) of home -> first, ..., last -> home; (N,) for an
            open path that ends at its last target.
        order: (N,) target indices in visiting order.
        path: the image file (PNG, PDF, SVG by extension); folders are created.
        title: the figure's title, saying what was run.
        q_home: optional (n,) home configuration: the arm's links are drawn there.
        scene: optional :class:`~subtask_opt.cell.scene.Scene`: its box edges and meshes
            are drawn (meshes simplified above :data:`FIGURE_TRIANGLES`), and its tool on
            the arm at home.
        detours: optional detoured legs
            (:func:`~subtask_opt.plotting.cell_geometry.detour_legs` of the trajectory):
            the TCP along them in purple with their waypoints as squares, their bars purple.

    Returns:
        The path written.

    Raises:
        ParameterError: shapes, non-finite or negative values, an order that is not a
            permutation.
    """
    import matplotlib.pyplot as plt

    fig = serial_tour_figure(arm, targets, tool_path, leg_times, order, title=title,
                             q_home=q_home, scene=scene, detours=detours)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out
