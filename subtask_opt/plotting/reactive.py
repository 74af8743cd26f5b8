"""Figures of reactive runs: trajectory with sonar beams, memberships over time, GIF."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from subtask_opt.planners.polygon.world import PolygonWorld
    from subtask_opt.planners.reactive.simulation import ReactiveRun


def _axes(ax: Axes | None, figsize: tuple[float, float]) -> tuple[Figure, Axes]:
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=figsize)
        return fig, ax
    return ax.figure, ax


def draw_world(ax: Axes, world: PolygonWorld) -> None:
    """Obstacles (grey) and the world boundary, equal aspect."""
    from matplotlib.patches import Polygon, Rectangle

    x0, y0, x1, y1 = world.bounds
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, lw=1.5, color="k"))
    for poly in world.obstacles:
        ax.add_patch(Polygon(poly, closed=True, fc="0.6", ec="0.25", lw=1))
    ax.set_xlim(x0 - 0.02 * (x1 - x0), x1 + 0.02 * (x1 - x0))
    ax.set_ylim(y0 - 0.02 * (y1 - y0), y1 + 0.02 * (y1 - y0))
    ax.set_aspect("equal")


def _beams(run: ReactiveRun, i: int) -> np.ndarray:
    """(n_beams, 2, 2) segments from the pose to each beam end at step i."""
    pose = run.poses[i]
    a = run.beam_angles + pose[2]
    r = run.scans[i]
    ends = np.column_stack([pose[0] + r * np.cos(a), pose[1] + r * np.sin(a)])
    starts = np.broadcast_to(pose[:2], ends.shape)
    return np.stack([starts, ends], axis=1)


def _draw_robot(ax: Axes, run: ReactiveRun, i: int, color: str = "C0", beams: bool = True,
                artists: list[Any] | None = None) -> list[Any]:
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Circle

    out = [] if artists is None else artists
    pose = run.poses[i]
    if beams:
        segs = _beams(run, i)
        hit = run.scans[i] < run.max_range
        colors = np.where(hit[:, None], [[0.85, 0.2, 0.1, 0.7]], [[0.2, 0.6, 0.2, 0.35]])
        out.append(ax.add_collection(LineCollection(segs, colors=colors, lw=0.8)))
    out.append(ax.add_patch(Circle(pose[:2], run.radius, fc="none", ec=color, lw=1.2)))
    h = pose[:2] + run.radius * np.array([np.cos(pose[2]), np.sin(pose[2])])
    out.extend(ax.plot([pose[0], h[0]], [pose[1], h[1]], color=color, lw=1.2))
    return out


def plot_run(world: PolygonWorld, run: ReactiveRun, *, ax: Axes | None = None,
             beams_every: int = 0, title: str | None = None) -> Figure:
    """The trajectory (wall-following steps highlighted), start, goal and sonar beams.

    Args:
        beams_every: draw the beams and the body every this many steps (0:
            about eight snapshots along the run).
    """
    fig, ax = _axes(ax, (6.5, 6.5))
    draw_world(ax, world)
    xy = run.poses[:, :2]
    ax.plot(xy[:, 0], xy[:, 1], "-", color="C0", lw=1.5, label="trajectory")
    if np.any(run.escaping):
        e = np.flatnonzero(run.escaping)
        ax.plot(xy[e + 1, 0], xy[e + 1, 1], ".", color="C1", ms=3, label="wall following")
    every = beams_every or max(1, run.steps // 8)
    for i in range(0, run.poses.shape[0], every):
        _draw_robot(ax, run, i)
    _draw_robot(ax, run, run.poses.shape[0] - 1, color="C3")
    from matplotlib.patches import Circle

    ax.add_patch(Circle(run.goal, run.goal_tolerance, fc="none", ec="C2", lw=1.2, ls="--"))
    ax.plot(*run.goal, "*", color="C2", ms=14, label="goal")
    ax.plot(*run.start[:2], "o", color="k", ms=5, label="start")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title or f"{run.navigator} on {run.world}: {run.outcome}, "
                 f"{run.steps} steps, path {run.path_length:.2f}")
    return fig


def plot_memberships(run: ReactiveRun, *, ax: Axes | None = None) -> Figure:
    """muG1, muG2, muG3 and muD of the chosen candidate per step, wall following shaded."""
    fig, ax = _axes(ax, (8.0, 3.2))
    t = np.arange(run.steps) * run.dt
    labels = (r"$\mu_{G1}$ clearance", r"$\mu_{G2}$ repulsion", r"$\mu_{G3}$ target",
              r"$\mu_D$ decision")
    for k, (lab, style) in enumerate(zip(labels, ("-", "-", "-", "k-"), strict=True)):
        ax.plot(t, run.mu[:, k], style, lw=2.0 if k == 3 else 1.0, label=lab)
    if np.any(run.escaping):
        ax.fill_between(t, 0, 1, where=run.escaping, color="C1", alpha=0.15, step="post",
                        label="wall following")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("membership")
    ax.set_ylim(0, 1.02)
    ax.legend(loc="lower right", fontsize=7, ncol=3)
    ax.set_title(f"memberships of the chosen via-point ({run.navigator})")
    fig.tight_layout()
    return fig


def animate_run(world: PolygonWorld, run: ReactiveRun, path: str | Path, *, fps: int = 10,
                every: int = 1, dpi: int = 80, progress: bool = False) -> Path:
    """Write a GIF of the run (robot, beams, trail) with matplotlib's PillowWriter.

    Args:
        every: one frame every this many steps (the last pose always has one).
        progress: show a progress bar over the frames.
    """
    import matplotlib.pyplot as plt
    from matplotlib.animation import PillowWriter

    from subtask_opt.base.errors import ParameterError
    from subtask_opt.base.progress import progress_bar

    if isinstance(every, bool) or not isinstance(every, int) or every < 1:
        raise ParameterError(f"animate_run.every must be an integer >= 1, got {every!r}")

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    draw_world(ax, world)
    ax.plot(*run.goal, "*", color="C2", ms=14)
    (trail,) = ax.plot([], [], "-", color="C0", lw=1.2)
    title = ax.set_title("")
    frames = list(range(0, run.poses.shape[0], every))
    if frames[-1] != run.poses.shape[0] - 1:
        frames.append(run.poses.shape[0] - 1)
    writer = PillowWriter(fps=fps)
    artists: list[Any] = []
    with writer.saving(fig, str(path), dpi=dpi), \
            progress_bar(progress, total=len(frames), desc="gif", unit="frame") as bar:
        for i in frames:
            for a in artists:
                a.remove()
            artists = []
            trail.set_data(run.poses[: i + 1, 0], run.poses[: i + 1, 1])
            esc = i > 0 and i - 1 < run.steps and bool(run.escaping[i - 1])
            _draw_robot(ax, run, i, color="C1" if esc else "C0", artists=artists)
            title.set_text(f"{run.navigator}  t = {i * run.dt:.1f} s"
                           + ("  (wall following)" if esc else ""))
            writer.grab_frame()
            bar.update()
    plt.close(fig)
    return path


def save_run_figure(world: PolygonWorld, run: ReactiveRun, path: str | Path) -> None:
    """The trajectory with its beams above the chosen candidates' memberships over time."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(7.0, 10.0), gridspec_kw={"height_ratios": [3, 1]})
    plot_run(world, run, ax=axes[0])
    plot_memberships(run, ax=axes[1])
    fig.savefig(path, dpi=110)
    plt.close(fig)
