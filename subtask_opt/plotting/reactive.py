"""Figures of reactive runs: trajectory with sonar beams, per-step signals, suites, GIF.

Coordinates are in metres (the reactive scenarios' unit), times in seconds.
Every figure names what was run in its title.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from subtask_opt.planners.polygon.world import PolygonWorld
    from subtask_opt.planners.reactive.fuzzy import Table1Report
    from subtask_opt.planners.reactive.simulation import ReactiveRun

_STYLE = {  # navigator -> (colour, line style): overlapping paths stay distinguishable
    "fuzzy": ("tab:blue", "-"),
    "fuzzy-no-escape": ("tab:purple", (0, (5, 2))),
    "vff": ("tab:orange", (0, (1, 1.5))),
    "vfh": ("tab:green", (0, (6, 2, 1, 2))),
}
_OUTCOME_COLOURS = {"success": "tab:green", "collision": "tab:red", "stall": "tab:orange",
                    "timeout": "tab:gray"}
_ECHO = (0.85, 0.2, 0.1, 0.7)
_NO_ECHO = (0.2, 0.6, 0.2, 0.35)


def _style(name: str, i: int = 0) -> tuple[str, Any]:
    return _STYLE.get(name, (f"C{i % 10}", "-"))


def _axes(ax: Axes | None, figsize: tuple[float, float]) -> tuple[Figure, Axes]:
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=figsize, layout="constrained")
        return fig, ax
    return ax.figure, ax  # type: ignore[return-value]


def save_figure(fig: Figure, path: str | Path, dpi: int = 110) -> Path:
    """Write ``fig`` to ``path`` (folders created) and close it."""
    return _save(fig, path, dpi)


def _save(fig: Figure, path: str | Path, dpi: int = 110) -> Path:
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def draw_world(ax: Axes, world: PolygonWorld) -> None:
    """Obstacles (grey) and the world boundary, equal aspect, axes in metres."""
    from matplotlib.patches import Polygon, Rectangle

    x0, y0, x1, y1 = world.bounds
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, lw=1.5, color="k"))
    for poly in world.obstacles:
        ax.add_patch(Polygon(poly, closed=True, fc="0.6", ec="0.25", lw=1))
    ax.set_xlim(x0 - 0.02 * (x1 - x0), x1 + 0.02 * (x1 - x0))
    ax.set_ylim(y0 - 0.02 * (y1 - y0), y1 + 0.02 * (y1 - y0))
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


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
        colors = np.where(hit[:, None], [_ECHO], [_NO_ECHO])
        out.append(ax.add_collection(LineCollection(list(segs), colors=colors, lw=0.8)))
    out.append(ax.add_patch(Circle(pose[:2], run.radius, fc="none", ec=color, lw=1.2)))
    h = pose[:2] + run.radius * np.array([np.cos(pose[2]), np.sin(pose[2])])
    out.extend(ax.plot([pose[0], h[0]], [pose[1], h[1]], color=color, lw=1.2))
    return out


def _legend_below(ax: Axes, handles: list[Any] | None = None, ncol: int = 3,
                  fontsize: int = 7) -> None:
    """A frameless legend a fixed 30 points under the axes (below the x label)."""
    from matplotlib.transforms import ScaledTranslation

    below = ax.transAxes + ScaledTranslation(0.0, -30.0 / 72.0, ax.figure.dpi_scale_trans)
    kw: dict[str, Any] = {} if handles is None else {"handles": handles}
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=below,
              fontsize=fontsize, ncol=ncol, frameon=False, **kw)


def _run_title(run: ReactiveRun) -> str:
    return (f"{run.navigator} on {run.world}: {run.outcome.value} after {run.steps} steps "
            f"({run.time:.0f} s), path {run.path_length:.2f} m")


def plot_run(world: PolygonWorld, run: ReactiveRun, *, ax: Axes | None = None,
             beams_every: int = 0, title: str | None = None) -> Figure:
    """The trajectory (wall-following steps highlighted), start, goal and sonar beams.

    Args:
        beams_every: draw the beams and the body every this many steps (0:
            about eight snapshots along the run).
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle

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
    ax.add_patch(Circle(tuple(run.goal), run.goal_tolerance, fc="none", ec="C2", lw=1.2,
                        ls="--"))
    ax.plot(*run.goal, "*", color="C2", ms=14, label=f"goal (tolerance {run.goal_tolerance:g} m)")
    ax.plot(*run.start[:2], "o", color="k", ms=5, label="start")
    handles, _ = ax.get_legend_handles_labels()
    handles += [Line2D([], [], color="C0", marker="o", mfc="none", ls="none", ms=8,
                       label=f"body (radius {run.radius:g} m)"),
                Line2D([], [], color="C3", marker="o", mfc="none", ls="none", ms=8,
                       label=f"final pose ({run.outcome.value})"),
                Line2D([], [], color=_ECHO, lw=1, label="sonar beam with echo"),
                Line2D([], [], color=_NO_ECHO, lw=1,
                       label=f"sonar beam, nothing within {run.max_range:g} m")]
    _legend_below(ax, handles)
    ax.set_title(title or _run_title(run), fontsize=10)
    return fig


def plot_memberships(run: ReactiveRun, *, ax: Axes | None = None) -> Figure:
    """muG1, muG2, muG3 and muD of the chosen candidate per step, wall following shaded.

    Only the fuzzy navigators have memberships; see :func:`plot_commands` for all.
    """
    from subtask_opt.base.errors import ParameterError

    if not np.any(np.isfinite(run.mu)):
        raise ParameterError(f"plot_memberships: the {run.navigator} run has no fuzzy "
                             "memberships (only the fuzzy navigators do)")
    fig, ax = _axes(ax, (8.0, 3.2))
    t = np.arange(run.steps) * run.dt
    labels = (r"$\mu_{G1}$ clearance", r"$\mu_{G2}$ repulsion", r"$\mu_{G3}$ target",
              r"$\mu_D$ decision")
    for k, (lab, style) in enumerate(zip(labels, ("-", "--", ":", "k-"), strict=True)):
        ax.plot(t, run.mu[:, k], style, lw=2.0 if k == 3 else 1.0, label=lab)
    if np.any(run.escaping):
        ax.fill_between(t, 0, 1, where=run.escaping, color="C1", alpha=0.15, step="post",
                        label="wall following")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("membership (0 to 1)")
    ax.set_ylim(0, 1.02)
    ax.legend(loc="lower right", fontsize=7, ncol=3)
    ax.set_title(f"memberships of the chosen via-point ({run.navigator} on {run.world})",
                 fontsize=10)
    return fig


def plot_commands(run: ReactiveRun, *, ax: Axes | None = None) -> Figure:
    """Speed (m/s, left axis), turn rate (rad/s, right axis) and the nearest echo (m,
    left axis) per step: the signals every navigator has."""
    fig, ax = _axes(ax, (8.0, 3.2))
    t = np.arange(run.steps) * run.dt
    nearest = run.scans[: run.steps].min(axis=1)
    lines: list[Any] = ax.plot(t, run.commands[:, 0], "-", color="C0", lw=1.2,
                               label="speed (m/s)")
    lines += ax.plot(t, nearest, "--", color="C3", lw=1.0, label="nearest echo (m)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("speed (m/s), nearest echo (m)")
    ax.set_ylim(bottom=0.0)
    right = ax.twinx()
    lines += right.plot(t, run.commands[:, 1], ":", color="C2", lw=1.2,
                        label="turn rate (rad/s, right axis)")
    right.set_ylabel("turn rate (rad/s)")
    if np.any(run.escaping):
        lines.append(ax.fill_between(t, 0, float(max(nearest.max(initial=0.0), 1e-9)),
                                     where=run.escaping, color="C1", alpha=0.15,
                                     step="post", label="wall following"))
    _legend_below(ax, lines, ncol=len(lines))
    ax.set_title(f"commands and nearest echo ({run.navigator} on {run.world})", fontsize=10)
    return fig


def save_run_figure(world: PolygonWorld, run: ReactiveRun, path: str | Path) -> Path:
    """Write :func:`run_figure` to ``path`` (folders created)."""
    return _save(run_figure(world, run), path)


def run_figure(world: PolygonWorld, run: ReactiveRun) -> Figure:
    """The trajectory with its beams above the per-step signals: the memberships
    (fuzzy navigators only) and the commands with the nearest echo."""
    import matplotlib.pyplot as plt

    fuzzy = bool(np.any(np.isfinite(run.mu)))
    rows = 3 if fuzzy else 2
    x0, y0, x1, y1 = world.bounds
    top = 6.0 * min(max((y1 - y0) / (x1 - x0), 0.3), 1.6) + 1.8   # map, title and legend
    fig, axes = plt.subplots(rows, 1, figsize=(7.5, top + 3.0 * (rows - 1)),
                             gridspec_kw={"height_ratios": [top] + [3.0] * (rows - 1)},
                             layout="constrained")
    plot_run(world, run, ax=axes[0])
    if fuzzy:
        plot_memberships(run, ax=axes[1])
    plot_commands(run, ax=axes[-1])
    return fig


def plot_paper_runs(runs: Mapping[str, tuple[PolygonWorld, Sequence[ReactiveRun]]], *,
                    title: str | None = None) -> Figure:
    """One panel per scenario with every navigator's trajectory overlaid (colour, dash and
    width per navigator, so identical paths stay visible; the legend under each panel
    gives each run's outcome and path length). Square worlds go two to a row, wide ones
    (more than twice as wide as tall) get a row of their own."""
    import matplotlib.pyplot as plt

    rows: list[list[str]] = []
    pending: list[str] = []
    for name, (world, _) in runs.items():
        x0, y0, x1, y1 = world.bounds
        if x1 - x0 > 2.0 * (y1 - y0):
            rows.append([name, name])
        else:
            pending.append(name)
            if len(pending) == 2:
                rows.append(pending)
                pending = []
    if pending:
        rows.append([pending[0], "."] if rows else [pending[0], pending[0]])
    rows.sort(key=lambda r: r[0] == r[1])          # wide panels last
    heights = [0.55 if r[0] == r[1] else 1.0 for r in rows]
    layout: Any = rows
    fig, axes = plt.subplot_mosaic(layout, figsize=(12.0, 5.6 * sum(heights) + 0.8),
                                   height_ratios=heights, layout="constrained")
    for name, (world, rs) in runs.items():
        ax = axes[name]
        draw_world(ax, world)
        for i, run in enumerate(rs):
            colour, dash = _style(run.navigator, i)
            wide = i == 0
            ax.plot(run.poses[:, 0], run.poses[:, 1], color=colour, ls=dash,
                    lw=4.0 if wide else 1.6, alpha=0.4 if wide else 0.95, zorder=2 + i,
                    label=f"{run.navigator}: {run.outcome.value}, {run.path_length:.1f} m")
            ax.plot(*run.poses[-1, :2], "o", color=colour, mfc="none", ms=7, zorder=2 + i)
        if rs:
            ax.plot(*rs[0].start[:2], "o", color="k", ms=5, label="start", zorder=10)
            ax.plot(*rs[0].goal, "*", color="red", ms=13, label="goal", zorder=10)
        _legend_below(ax, fontsize=8)
        ax.set_title(f"scenario {name}", fontsize=10)
    fig.suptitle(title or "reactive navigators on the paper's scenarios (sonar ring, 18 beams)",
                 fontsize=11)
    return fig


def save_suite_figure(table: Mapping[str, Mapping[str, Any]], path: str | Path, *,
                      title: str = "") -> Path:
    """Stacked bars of the outcomes per navigator (from ``bench reactive``'s table) beside
    the mean path ratio of the successful runs."""
    import matplotlib.pyplot as plt

    names = list(table)
    x = np.arange(len(names))
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11.0, 4.2),
                                  gridspec_kw={"width_ratios": [1.4, 1]})
    bottom = np.zeros(len(names))
    for key, outcome in (("success", "success"), ("collisions", "collision"),
                         ("stalls", "stall"), ("timeouts", "timeout")):
        counts = np.array([table[n][key] for n in names], dtype=float)
        ax.bar(x, counts, bottom=bottom, color=_OUTCOME_COLOURS[outcome], label=outcome)
        bottom += counts
    ax.set_xticks(x, names)
    ax.set_xlabel("navigator")
    ax.set_ylabel("runs")
    ax.legend(fontsize=8, loc="lower right", framealpha=0.85)
    ax.set_title("outcome of every run", fontsize=10)
    ratio = np.array([table[n]["mean_path_ratio"] for n in names], dtype=float)
    colours = [_style(n, i)[0] for i, n in enumerate(names)]
    ax2.bar(x, np.nan_to_num(ratio, nan=0.0), color=colours)
    ax2.axhline(1.0, color="k", lw=0.8, ls="--", label="shortest path (visibility graph)")
    for xi, r in zip(x, ratio, strict=True):
        ax2.annotate("n/a" if not np.isfinite(r) else f"{r:.2f}", (xi, r if np.isfinite(r)
                                                                    else 0.0),
                     ha="center", va="bottom", fontsize=8)
    ax2.set_xticks(x, names)
    ax2.set_xlabel("navigator")
    ax2.set_ylabel("mean path ratio (successful runs)")
    ax2.legend(fontsize=8, loc="lower right", framealpha=0.85)
    ax2.set_title("path length over the shortest path", fontsize=10)
    fig.suptitle(f"bench reactive: {title}" if title else "bench reactive", fontsize=11)
    fig.tight_layout()
    return _save(fig, path)


def save_table1_figure(report: Table1Report, path: str | Path) -> Path:
    """Seed paper 001's Table 1: the paper's decision memberships beside ours."""
    import matplotlib.pyplot as plt

    k = len(report.mu_d)
    x = np.arange(1, k + 1)
    fig, ax = plt.subplots(figsize=(7.0, 3.8))
    ax.bar(x - 0.2, report.paper_mu_d, width=0.4, color="0.6", label=r"paper $\mu_D$")
    ax.bar(x + 0.2, report.mu_d, width=0.4, color="tab:blue", label=r"recomputed $\mu_D$")
    ax.plot(report.choice + 0.2, report.mu_d[report.choice - 1] + 0.03, "v", color="tab:red",
            label=f"our choice (candidate {report.choice})")
    ax.plot(report.paper_choice - 0.2, report.paper_mu_d[report.paper_choice - 1] + 0.03, "v",
            color="k", mfc="none", label=f"paper's choice (candidate {report.paper_choice})")
    ax.set_xticks(x)
    ax.set_xlabel("via-point candidate")
    ax.set_ylabel(r"decision membership $\mu_D$")
    ax.set_ylim(0, 1)
    ax.legend(fontsize=8, loc="upper right")
    w = ", ".join(f"{v:.3g}" for v in report.weights)
    ax.set_title(f"seed paper 001 Table 1: min of weighted memberships, weights ({w})",
                 fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def animate_run(world: PolygonWorld, run: ReactiveRun, path: str | Path, *, fps: int = 10,
                every: int = 1, dpi: int = 80, progress: bool = False) -> Path:
    """Write a GIF of the run (robot, beams, trail) with matplotlib's PillowWriter.

    Args:
        every: one frame every this many steps (the last pose always has one).
        progress: show a progress bar over the frames (on a terminal only).
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
    ax.plot(*run.goal, "*", color="C2", ms=14, label="goal")
    (trail,) = ax.plot([], [], "-", color="C0", lw=1.2, label="trajectory")
    ax.legend(loc="upper left", fontsize=7)
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
            title.set_text(f"{run.navigator} on {run.world}  t = {i * run.dt:.1f} s"
                           + ("  (wall following)" if esc else ""))
            writer.grab_frame()
            bar.update()
    plt.close(fig)
    return path
