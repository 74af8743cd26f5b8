"""Figures of the AGV family: quadtree, local-map states, routes, and a GIF of a run."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from subtask_opt.planners.agv.quadtree import Quadtree
    from subtask_opt.planners.agv.scenarios import SuiteReport
    from subtask_opt.planners.agv.simulation import AgvRun

_OBSTACLE_COLOURS = ("C3", "C1", "C4", "C5", "C6", "C8")
_EVENT_MARKERS = {"brake": ("v", "C3"), "wait": ("s", "C3"), "speed_up": ("^", "C2"),
                  "back_off": ("<", "C1"),
                  "sidestep": ("D", "C1"), "static": ("X", "k"), "replan": ("P", "C4"),
                  "recovery": ("*", "C2"), "check_point": ("+", "C9"), "blocked": ("x", "k"),
                  "collision": ("X", "r")}
_EVENT_LABELS = {"brake": "brake / stop", "wait": "wait", "speed_up": "speed up",
                 "back_off": "back off",
                 "sidestep": "sidestep", "static": "obstacle taken as static",
                 "replan": "re-plan", "recovery": "route recovered",
                 "check_point": "check point (eq. 3)", "blocked": "blocked",
                 "collision": "collision"}


def _axes(ax: Axes | None, figsize: tuple[float, float] = (6, 6)) -> tuple[Figure, Axes]:
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=figsize)
        return fig, ax
    return cast("Figure", ax.figure), ax


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
    ax.set_xlabel("x (cells, 1 cell = 1 u = 10 px)")
    ax.set_ylabel("y (cells, down as in the image)")


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
    from matplotlib.patches import Patch

    handles: list[Any] = [Patch(fc="white", ec="C0", label="white leaf (free)"),
                          Patch(fc="0.15", ec="C0", label="black leaf (obstacle)")]
    if tree.count(GREY):
        handles.append(Patch(fc="0.6", ec="C0", label="grey leaf (mixed, finest size)"))
    if path is not None and len(path):
        (line,) = ax.plot(path[:, 0], path[:, 1], "-o", color="C3", ms=3, lw=1.5,
                          label="quadtree path")
        handles.append(line)
    ax.legend(handles=handles, loc="upper right", fontsize=7, framealpha=0.9)
    ax.set_title(title or f"quadtree of the map: {len(tree.leaves)} leaves, "
                          f"depth {tree.depth()}")
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
    ax.set_xlabel("x (cells)")
    ax.set_ylabel("y (cells, down as in the image)")
    ax.set_title("2-bit local map (b1 b2): only 00 cells are routable")
    return fig


def plot_run(run: AgvRun, *, ax: Axes | None = None, corners: bool = True,
             title: str | None = None) -> Figure:
    """Planned route, driven trajectory (and the believed one under drift),
    obstacle tracks with start and end, and the events where they happened."""
    fig, ax = _axes(ax, (7, 7))
    draw_grid(ax, run.world.occupancy, run.static_cells)
    if corners:
        from subtask_opt.planners.agv.navigation import near_points

        pts = near_points(run.world.occupancy)
        if len(pts):
            ax.plot(pts[:, 0], pts[:, 1], ".", color="0.55", ms=3,
                    label="near points (corner sub-goals)")
    if run.static_cells.any():
        ax.plot([], [], "s", color=(0.65, 0.45, 0.3), ms=9,
                label="cells of an obstacle taken as static")
    r = run.planned_route
    ax.plot(r[:, 0], r[:, 1], "--o", color="C0", lw=1.4, ms=4, alpha=0.9, zorder=4,
            label="planned route (sub-goals)")
    tr = run.trajectory
    ax.plot(tr[:, 0], tr[:, 1], "-", color="C2", lw=3.5, alpha=0.6, label="AGV (driven)")
    if run.params.drift:
        b = run.believed
        ax.plot(b[:, 0], b[:, 1], ":", color="k", lw=1.2,
                label="AGV (believed, odometry)")
    for j, track in enumerate(run.obstacle_positions):
        c = _OBSTACLE_COLOURS[j % len(_OBSTACLE_COLOURS)]
        ax.plot(track[:, 0], track[:, 1], "-", color=c, lw=1.2, alpha=0.8,
                label=f"obstacle {j} track")
        ax.plot(track[0, 0], track[0, 1], ">", color=c, ms=6, mec="k", mew=0.4)
        ax.plot(track[-1, 0], track[-1, 1], "o", color=c, ms=7, mec="k", mew=0.4)
    used: dict[tuple[int, int], int] = {}  # events at one place are stacked upwards
    for kind, (marker, colour) in _EVENT_MARKERS.items():
        ev = [e for e in run.events if e.kind == kind]
        if ev:
            xy = np.array([_at(run, e.time) for e in ev])
            for i, (x, y) in enumerate(xy):
                key = (int(round(x)), int(round(y)))
                if kind != "check_point":
                    xy[i, 1] = y - 0.9 * used.get(key, 0)
                    used[key] = used.get(key, 0) + 1
            ax.plot(xy[:, 0], xy[:, 1], marker, color=colour, ms=9, mec="k", mew=0.6,
                    label=_EVENT_LABELS[kind], ls="none")
    ax.plot(*tr[0], "s", color="C0", ms=9, mec="k", ls="none", label="start")
    ax.plot(*r[-1], "*", color="gold", mec="k", ms=15, ls="none", label="goal")
    n_obs = len(run.obstacle_positions)
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8, framealpha=0.9,
              title="obstacles: > start, o end" if n_obs else None, title_fontsize=7)
    if title is None:
        p = run.params
        opts = [f"t-second check {'on' if p.collision_check else 'OFF'}"]
        if p.drift:
            opts.append(f"drift on (seed {run.seed}), check points "
                        f"{'on' if p.check_points else 'off'}")
        delay = f", delay {run.delay_s:.1f} s" if run.success else ""
        obs = (f"{n_obs} moving obstacle(s), AGV at {p.v_nominal:g} u/s" if n_obs
               else f"static obstacles only, AGV at {p.v_nominal:g} u/s")
        title = (f"AGV scenario {run.scenario}: {run.outcome.value} at t = {run.time_s:.1f} s"
                 f"{delay}\n{', '.join(opts)}; {obs}")
    ax.set_title(title, fontsize=10)
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
    (trail,) = ax.plot([], [], "-", color="C2", lw=2, label="AGV")
    agv = Circle(tuple(run.trajectory[0]), radius, fc="C2", ec="k")
    ax.add_patch(agv)
    obs = [Circle(tuple(p[0]), radius, fc=_OBSTACLE_COLOURS[j % 6], ec="k",
                  label=f"obstacle {j}") for j, p in enumerate(run.obstacle_positions)]
    for c in obs:
        ax.add_patch(c)
    ax.legend(loc="upper right", fontsize=7)
    text = ax.text(0.01, 0.01, "", transform=ax.transAxes, fontsize=8, va="bottom",
                   bbox={"fc": "white", "alpha": 0.8, "ec": "none"})
    ax.set_title(f"AGV scenario {run.scenario}: {run.outcome.value} in {run.time_s:.1f} s")

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
    """:func:`plot_run` beside the speed profile, written to ``path``."""
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(13, 7))
    grid = fig.add_gridspec(2, 2, width_ratios=(1.45, 1), height_ratios=(1, 1))
    plot_run(run, ax=fig.add_subplot(grid[:, 0]))
    ax = fig.add_subplot(grid[0, 1])
    ax.plot(run.times, run.speeds, color="C2", label="AGV speed")
    ax.axhline(run.params.v_nominal, color="0.5", ls="--", lw=1, label="normal speed")
    for e in run.events:
        if e.kind in _EVENT_MARKERS and e.kind != "check_point":
            ax.axvline(e.time, color=_EVENT_MARKERS[e.kind][1], lw=0.8, alpha=0.6)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("speed (cells/s = u/s)")
    ax.set_title("speed; vertical lines: events (colours as in the map)", fontsize=9)
    ax.legend(fontsize=8, loc="lower right")
    ax2 = fig.add_subplot(grid[1, 1])
    if len(run.obstacle_positions):
        d = run.obstacle_positions - run.trajectory[None, :, :]
        sep = np.hypot(d[..., 0], d[..., 1]).min(axis=0)
        ax2.plot(run.times, sep, color="C3", label="nearest obstacle")
        ax2.axhline(run.params.safety_distance, color="C1", ls="--", lw=1,
                    label="safety distance (factor D)")
        ax2.axhline(run.params.collision_distance, color="r", ls=":", lw=1,
                    label="collision distance")
        ax2.set_ylim(0, min(float(sep.max()) + 1, 20))
        ax2.set_ylabel("separation (cells)")
        ax2.set_title("distance to the nearest moving obstacle", fontsize=9)
    else:
        ax2.plot(run.times, run.drift_error, color="k", label="|true - believed|")
        ax2.set_ylabel("position error (cells)")
        ax2.set_title("odometry position error", fontsize=9)
    ax2.set_xlabel("time (s)")
    ax2.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def plot_suite(report: SuiteReport) -> Figure:
    """Three panels of a random suite: outcomes, delays, and the drift error
    per run with and without check points."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    ax = axes[0]
    names = ["success", "collision", "timeout", "no_path"]
    counts = [sum(o == n for o in report.outcomes) for n in names]
    x = np.arange(len(names))
    ax.bar(x - 0.2 if report.drift else x, counts, width=0.4, color="C2",
           label="with check points" if report.drift else "runs")
    if report.drift:
        bare = [report.success_no_check, report.collisions_no_check]
        ax.bar(x[:2] + 0.2, bare, width=0.4, color="C7", label="without check points")
    ax.set_xticks(x, names)
    ax.set_ylabel("runs")
    ax.set_xlabel("outcome")
    ax.set_title("outcomes", fontsize=10)
    ax.legend(fontsize=8)
    ax = axes[1]
    delays = np.array([d for d in report.delays if np.isfinite(d)])
    if len(delays):
        ax.hist(delays, bins=20, color="C0", label=f"successful runs ({len(delays)})")
        ax.axvline(float(delays.mean()), color="k", ls="--",
                   label=f"mean {delays.mean():.2f} s")
    ax.set_xlabel("delay: arrival minus obstacle-free arrival (s)")
    ax.set_ylabel("runs")
    ax.set_title("delay caused by the moving obstacles", fontsize=10)
    ax.legend(fontsize=8)
    ax = axes[2]
    if report.drift and report.drift_errors_no_check:
        a = np.array(report.drift_errors)
        b = np.array(report.drift_errors_no_check)
        bins = np.linspace(0, max(float(a.max()), float(b.max())) + 1e-9, 25)
        ax.hist(b, bins=bins, color="C7", alpha=0.7,
                label=f"without check points (mean {b.mean():.2f})")
        ax.hist(a, bins=bins, color="C2", alpha=0.7,
                label=f"with check points (mean {a.mean():.2f})")
        ax.set_xlabel("mean |true - believed position| of a run (cells)")
        ax.set_ylabel("runs")
        ax.legend(fontsize=8)
    else:
        ax.text(0.5, 0.5, "drift off: no position error", ha="center", va="center",
                transform=ax.transAxes)
        ax.set_xlabel("position error (cells)")
        ax.set_ylabel("runs")
    ax.set_title("odometry drift error per run", fontsize=10)
    check = "on" if report.collision_check else "OFF"
    drift = "on" if report.drift else "off"
    fig.suptitle(f"AGV random suite: {report.runs} runs from seed {report.seed} "
                 f"(t-second check {check}, odometry drift {drift})", fontsize=11)
    fig.tight_layout()
    return fig


def save_suite_figure(report: SuiteReport, path: str | Path) -> None:
    """:func:`plot_suite` written to ``path``."""
    import matplotlib.pyplot as plt

    fig = plot_suite(report)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
