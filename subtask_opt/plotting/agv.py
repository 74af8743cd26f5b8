"""Figures of the AGV family: quadtree, local-map states, routes, and a GIF of a run."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from subtask_opt.planners.agv.quadtree import Quadtree
    from subtask_opt.planners.agv.simulation import AgvRun

_OBSTACLE_COLOURS = ("C3", "C1", "C4", "C5", "C6", "C8")
_EVENT_MARKERS = {"brake": ("v", "C3"), "wait": ("s", "C3"), "speed_up": ("^", "C2"),
                  "sidestep": ("D", "C1"), "static": ("X", "k"), "replan": ("P", "C4"),
                  "recovery": ("*", "C2"), "collision": ("X", "r")}


def _axes(ax: Axes | None, figsize: tuple[float, float] = (6, 6)) -> tuple[Figure, Axes]:
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=figsize)
        return fig, ax
    return ax.figure, ax


def draw_grid(ax: Axes, occupancy: np.ndarray, extra: np.ndarray | None = None) -> None:
    """Blocked cells dark grey (``extra`` cells, e.g. static obstacles, in brown);
    cell (x, y) centred at (x, y), y down as in the image."""
    occ = np.asarray(occupancy, dtype=bool)
    img = np.ones(occ.shape + (3,))
    img[occ] = 0.35
    if extra is not None:
        img[np.asarray(extra, dtype=bool)] = (0.65, 0.45, 0.3)
    h, w = occ.shape
    ax.imshow(img, extent=(-0.5, w - 0.5, h - 0.5, -0.5), interpolation="nearest")
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.set_aspect("equal")


def plot_quadtree(tree: Quadtree, occupancy: np.ndarray, *, path: np.ndarray | None = None,
                  ax: Axes | None = None, title: str | None = None) -> Figure:
    """Leaves of a quadtree: white (free), black (obstacle), grey (mixed at the
    finest size) squares with their outlines, and an optional path."""
    from matplotlib.patches import Rectangle

    from subtask_opt.planners.agv.quadtree import BLACK, GREY

    fig, ax = _axes(ax)
    draw_grid(ax, occupancy)
    for x0, y0, size, colour, _ in tree.leaves:
        fc = {BLACK: "0.15", GREY: "0.6"}.get(int(colour), "none")
        ax.add_patch(Rectangle((x0 - 0.5, y0 - 0.5), size, size, fc=fc, ec="C0", lw=0.5,
                               alpha=0.9 if fc != "none" else 1.0))
    if path is not None and len(path):
        ax.plot(path[:, 0], path[:, 1], "-o", color="C3", ms=3, lw=1.5, label="path")
        ax.legend(loc="upper right", fontsize=8)
    ax.set_title(title or f"quadtree: {len(tree.leaves)} leaves, depth {tree.depth()}")
    return fig


def plot_local_states(states: np.ndarray, *, ax: Axes | None = None) -> Figure:
    """The 2-bit local-map states in four colours."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    from subtask_opt.planners.agv.certainty_grid import STATE_NAMES

    fig, ax = _axes(ax)
    colours = ["white", "#9ecae1", "#fd8d3c", "#252525"]
    h, w = states.shape
    ax.imshow(states, cmap=ListedColormap(colours), vmin=0, vmax=3, interpolation="nearest",
              extent=(-0.5, w - 0.5, h - 0.5, -0.5))
    ax.legend(handles=[Patch(fc=c, ec="0.5", label=f"{k:02b} {STATE_NAMES[k]}")
                       for k, c in enumerate(colours)], loc="upper right", fontsize=7)
    ax.set_title("local map (b1 b2)")
    return fig


def plot_run(run: AgvRun, *, ax: Axes | None = None, corners: bool = True,
             title: str | None = None) -> Figure:
    """Planned route, driven trajectory, obstacle tracks, and the events."""
    fig, ax = _axes(ax)
    draw_grid(ax, run.world.occupancy, run.static_cells)
    if corners:
        from subtask_opt.planners.agv.simulation import near_points

        pts = near_points(run.world.occupancy)
        if len(pts):
            ax.plot(pts[:, 0], pts[:, 1], ".", color="0.6", ms=3, label="near points")
    r = run.planned_route
    ax.plot(r[:, 0], r[:, 1], "--o", color="C0", lw=1, ms=4, alpha=0.7, label="planned route")
    tr = run.trajectory
    ax.plot(tr[:, 0], tr[:, 1], "-", color="C2", lw=2, label="AGV")
    for j, track in enumerate(run.obstacle_positions):
        c = _OBSTACLE_COLOURS[j % len(_OBSTACLE_COLOURS)]
        ax.plot(track[:, 0], track[:, 1], "-", color=c, lw=1, alpha=0.7)
        ax.plot(track[-1, 0], track[-1, 1], "o", color=c, ms=6)
    for kind, (marker, colour) in _EVENT_MARKERS.items():
        ev = [e for e in run.events if e.kind == kind]
        if ev:
            xy = np.array([_at(run, e.time) for e in ev])
            ax.plot(xy[:, 0], xy[:, 1], marker, color=colour, ms=8, mec="k", mew=0.5,
                    label=kind, ls="none")
    ax.plot(*tr[0], "s", color="C0", ms=8)
    ax.plot(*r[-1], "*", color="gold", mec="k", ms=14)
    ax.legend(loc="lower right", fontsize=7, framealpha=0.8)
    ax.set_title(title or f"{run.scenario}: {run.outcome} in {run.time_s:.1f} s")
    return fig


def _at(run: AgvRun, t: float) -> np.ndarray:
    i = int(np.clip(np.searchsorted(run.times, t), 0, len(run.times) - 1))
    return run.trajectory[i]


def animate_run(run: AgvRun, out: str | Path, *, fps: int = 10, max_frames: int = 160,
                dpi: int = 80) -> Path:
    """Write a GIF of a run (matplotlib's PillowWriter): map, planned route,
    AGV and obstacles as discs of the collision size, and the last event."""
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.patches import Circle

    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    n = len(run.times)
    frames = np.unique(np.linspace(0, n - 1, min(n, max_frames)).round().astype(int))
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    static_at = next((e.time for e in run.events if e.kind == "static"), None)
    draw_grid(ax, run.world.occupancy)
    static_img = None
    if static_at is not None:
        overlay = np.zeros(run.static_cells.shape + (4,))
        overlay[run.static_cells] = (0.65, 0.45, 0.3, 0.8)
        h, w = run.static_cells.shape
        static_img = ax.imshow(overlay, extent=(-0.5, w - 0.5, h - 0.5, -0.5),
                               interpolation="nearest", visible=False)
    r = run.planned_route
    ax.plot(r[:, 0], r[:, 1], "--", color="C0", lw=1, alpha=0.6)
    ax.plot(*r[-1], "*", color="gold", mec="k", ms=14)
    radius = run.params.collision_distance / 2
    (trail,) = ax.plot([], [], "-", color="C2", lw=2)
    agv = ax.add_patch(Circle(tuple(run.trajectory[0]), radius, fc="C2", ec="k"))
    obs = [ax.add_patch(Circle(tuple(p[0]), radius, fc=_OBSTACLE_COLOURS[j % 6], ec="k"))
           for j, p in enumerate(run.obstacle_positions)]
    text = ax.text(0.01, 0.01, "", transform=ax.transAxes, fontsize=8, va="bottom",
                   bbox={"fc": "white", "alpha": 0.8, "ec": "none"})
    ax.set_title(f"{run.scenario}: {run.outcome} in {run.time_s:.1f} s")

    def update(i: int) -> list[Any]:
        t = run.times[i]
        trail.set_data(run.trajectory[:i + 1, 0], run.trajectory[:i + 1, 1])
        agv.center = tuple(run.trajectory[i])
        for j, c in enumerate(obs):
            c.center = tuple(run.obstacle_positions[j, i])
        if static_img is not None:
            static_img.set_visible(t >= static_at)
        last = [e for e in run.events if e.time <= t + 1e-9 and e.kind != "subgoal"]
        label = f"{last[-1].kind} {last[-1].detail}".strip() if last else ""
        text.set_text(f"t = {t:5.2f} s  v = {run.speeds[i]:.2f}\n{label}")
        return [trail, agv, text, *obs]

    anim = FuncAnimation(fig, update, frames=frames, blit=False)
    anim.save(str(out), writer=PillowWriter(fps=fps), dpi=dpi)
    plt.close(fig)
    return out


def save_run_figure(run: AgvRun, path: str | Path) -> None:
    """:func:`plot_run` written to ``path``."""
    import matplotlib.pyplot as plt

    fig = plot_run(run)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
