"""Figures of a sequencing result: the tour over the workspace, convergence.

These are the paper's Figs. 7-13: the initial and the optimal tour of the
subtasks, and the fitness (total travel time) against generation.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from subtask_opt.arm.sequencing import Result, SequencingProblem


def plot_workspace(ax: Axes, arm) -> None:
    """Shade the arm's reachable annulus and mark its base."""
    from matplotlib.patches import Circle

    bx, by = arm.base_xy
    ax.add_patch(Circle((bx, by), arm.r_max, color="tab:blue", alpha=0.07, lw=0))
    ax.add_patch(Circle((bx, by), arm.r_max, fill=False, ec="tab:blue", lw=0.8, alpha=0.5))
    if arm.r_min > 0:
        ax.add_patch(Circle((bx, by), arm.r_min, color="white", lw=0))
        ax.add_patch(Circle((bx, by), arm.r_min, fill=False, ec="tab:blue", lw=0.8, ls="--",
                            alpha=0.5))
    ax.plot([bx], [by], marker="s", color="k", ms=6)


def plot_tour(problem: SequencingProblem, order: np.ndarray, *, ax: Axes | None = None,
              title: str | None = None, draw_arm: bool = True,
              configurations: np.ndarray | None = None) -> Axes:
    """Draw a closed tour through the subtasks, with the arm posed at each subtask.

    Args:
        problem: gives the points and the arm.
        order: the tour (any permutation, e.g. ``result.order`` or the input
            order as the "initial tour").
        ax: axes to draw into (a new figure if None).
        draw_arm: draw the arm links at every subtask, in the configuration
            used (``configurations`` or the problem's).
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    pts = problem.subtasks.points
    arm = problem.arm
    if arm is not None:
        plot_workspace(ax, arm)
    order = np.asarray(order, dtype=int)
    closed = np.append(order, order[0])
    ax.plot(pts[closed, 0], pts[closed, 1], "-", color="tab:red", lw=1.4, zorder=3)
    for a, b in zip(closed[:-1], closed[1:], strict=True):
        mid = (pts[a] + pts[b]) / 2
        d = pts[b] - pts[a]
        ax.annotate("", xy=mid + 0.08 * d, xytext=mid - 0.08 * d,
                    arrowprops=dict(arrowstyle="->", color="tab:red", lw=1.2), zorder=4)
    if draw_arm and arm is not None:
        configs = (np.asarray(configurations) if configurations is not None
                   else problem.timing.configurations)
        for i, p in enumerate(pts):
            q = arm.ik(p)[int(configs[i])]
            if np.all(np.isfinite(q)):
                joints = arm.link_points(q)
                ax.plot(joints[:, 0], joints[:, 1], "-", color="0.55", lw=0.7, alpha=0.6,
                        zorder=2)
    ax.scatter(pts[:, 0], pts[:, 1], s=28, color="k", zorder=5)
    ax.scatter(pts[order[0], 0], pts[order[0], 1], s=90, facecolor="none", edgecolor="tab:green",
               lw=2, zorder=6, label="first subtask")
    for i, p in enumerate(pts):
        ax.annotate(str(i), p, textcoords="offset points", xytext=(4, 4), fontsize=7, zorder=6)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if title:
        ax.set_title(title)
    ax.legend(loc="upper right", fontsize=8)
    return ax


def plot_convergence(result: Result, *, ax: Axes | None = None,
                     optimum: float | None = None) -> Axes:
    """Total travel time of the best tour (and the population mean) per generation."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4))
    h = result.history
    gens = np.arange(1, h.generations + 1)
    ax.plot(gens, h.mean_cost, color="0.6", lw=0.8, label="population mean")
    ax.plot(gens, h.best_cost, color="tab:blue", lw=1.6, label="best so far")
    for i, g in enumerate(h.restarts):
        ax.axvline(g, color="tab:orange", lw=0.5, alpha=0.4,
                   label="restart" if i == 0 else None)
    if optimum is not None:
        ax.axhline(optimum, color="tab:green", ls="--", lw=1, label="certified optimum")
    ax.set_xlabel("generation")
    ax.set_ylabel("total travel time [s]")
    ax.set_title(f"{result.preset} preset: {result.generations} generations, "
                 f"{result.restarts} restarts")
    ax.legend(fontsize=8)
    return ax


def solution_figure(result: Result, problem: SequencingProblem) -> Figure:
    """Initial tour (input order), optimised tour and convergence side by side."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(17, 5.6))
    n = problem.size
    initial = np.arange(n)
    t0 = problem.tour_time(initial)
    plot_tour(problem, initial, ax=axes[0], draw_arm=False,
              title=f"input order: {t0:.3f} s")
    plot_tour(problem, result.order, ax=axes[1], configurations=result.configurations,
              title=f"optimised ({result.time_model} model): {result.total_time:.3f} s")
    plot_convergence(result, ax=axes[2])
    fig.tight_layout()
    return fig


def save_solution_figure(result: Result, problem: SequencingProblem, path: str | Path) -> Path:
    """Write :func:`solution_figure` to ``path`` (PNG, PDF, SVG by extension)."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = solution_figure(result, problem)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
