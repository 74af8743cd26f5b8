"""Figures of polygon worlds: obstacles, MAKLINK links and cells, the graph, paths.

``draw_*`` functions draw onto a given axes; :func:`figure` builds a one-panel
map (the paper's Figs. 1-4), :func:`planner_figure` a map plus the PSO
convergence (gap to the exact optimum, log scale), and :func:`save` writes a
figure to a file. World coordinates are in metres, as in the seed paper.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from subtask_opt.base.results import PlanResult
    from subtask_opt.planners.polygon.maklink import MaklinkGraph
    from subtask_opt.planners.polygon.world import PolygonWorld

# Overlapping paths stay distinguishable: the optimum is a wide translucent band
# under the others, which are thinner and dashed differently.
_PATH_STYLES: dict[str, dict[str, Any]] = {
    "dijkstra": dict(color="tab:orange", ls="--", lw=1.6),
    "improved": dict(color="tab:green", ls="-.", lw=1.6),
    "pso": dict(color="tab:red", ls="-", lw=1.4),
    "visibility": dict(color="tab:purple", ls="-", lw=6.0, alpha=0.3, solid_capstyle="round"),
}


def draw_world(ax: Any, world: PolygonWorld, *, label_obstacles: bool = True) -> None:
    """Bounds and filled obstacles (numbered when ``label_obstacles``)."""
    from matplotlib.patches import Polygon, Rectangle

    from subtask_opt.planners.polygon.world import interior_point

    x0, y0, x1, y1 = world.bounds
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, lw=1.2, color="black"))
    for i, poly in enumerate(world.obstacles):
        ax.add_patch(Polygon(poly, closed=True, fc="0.55", ec="0.2", lw=1.0, zorder=2))
        if label_obstacles:
            c = poly.mean(axis=0)
            if world.obstacle_at(c) != i:  # a non-convex polygon's vertex mean may lie outside
                c = interior_point(poly)
            ax.text(c[0], c[1], str(i), ha="center", va="center", color="white",
                    fontsize=8, zorder=3)
    pad = 0.02 * max(x1 - x0, y1 - y0)
    ax.set_xlim(x0 - pad, x1 + pad)
    ax.set_ylim(y0 - pad, y1 + pad)
    ax.set_aspect("equal")


def draw_links(ax: Any, graph: MaklinkGraph, *, cells: bool = False) -> None:
    """The free links (the paper's Fig. 1), optionally the convex cells shaded."""
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Polygon

    if cells:
        cmap = _cmap()
        for i, cell in enumerate(graph.cells):
            ax.add_patch(Polygon(cell, closed=True, fc=cmap(i % 20), alpha=0.25, lw=0, zorder=0))
    segs = list(graph.links.reshape(-1, 2, 2))
    ax.add_collection(LineCollection(segs, colors="tab:blue", lw=0.9, zorder=1, alpha=0.7,
                                     label="MAKLINK free links"))


def draw_graph(ax: Any, graph: MaklinkGraph, start: Any = None, goal: Any = None) -> None:
    """Link midpoints and the graph edges between them (the paper's Fig. 2)."""
    from matplotlib.collections import LineCollection

    mids = graph.midpoints
    pairs = graph.graph_edges()
    segs = [np.array([mids[i], mids[j]]) for i, j in pairs]
    for p in (start, goal):
        if p is None:
            continue
        p = np.asarray(p, dtype=float)
        for c in graph.cells_containing(p):
            segs += [np.array([p, mids[k]]) for k in graph.cell_links[c]]
    if segs:
        ax.add_collection(LineCollection(segs, colors="0.35", lw=0.6, zorder=1))
    for p, marker, color in ((start, "s", "tab:green"), (goal, "*", "tab:red")):
        if p is not None:
            ax.plot(*np.asarray(p, dtype=float), marker, color=color, ms=9, zorder=5)
    ax.plot(mids[:, 0], mids[:, 1], "o", ms=3.5, color="tab:blue", zorder=3,
            label="link midpoints")


def draw_path(ax: Any, path: np.ndarray, label: str = "", **style: Any) -> None:
    """A polyline with its end points marked."""
    path = np.asarray(path, dtype=float)
    if len(path) == 0:
        return
    ax.plot(path[:, 0], path[:, 1], label=label, zorder=4, **style)
    ax.plot(*path[0], "s", color="tab:green", ms=7, zorder=5)
    ax.plot(*path[-1], "*", color="tab:red", ms=11, zorder=5)


def figure(world: PolygonWorld, *, graph: MaklinkGraph | None = None,
           results: Mapping[str, PlanResult] | None = None, show_graph: bool = False,
           show_cells: bool = False, title: str = "", ax: Any = None) -> Any:
    """One panel: the world, optionally its links/cells/graph, and labelled paths.

    Returns the matplotlib Figure.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(6, 6))
    else:
        fig = ax.figure
    draw_world(ax, world)
    if graph is not None:
        draw_links(ax, graph, cells=show_cells)
        if show_graph:
            ends = [r.path for r in (results or {}).values() if r.success]
            start, goal = (ends[0][0], ends[0][-1]) if ends else (None, None)
            draw_graph(ax, graph, start, goal)
    for name, res in (results or {}).items():
        if res.success:
            style = _PATH_STYLES.get(res.planner, {})
            draw_path(ax, res.path, label=f"{name}: {res.length:.2f} m", **style)
        else:
            ax.plot([], [], " ", label=f"{name}: no path")
    if results or graph is not None:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=2, fontsize=8,
                  frameon=False)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or world.name)
    return fig


def convergence(history_best: np.ndarray, optimum: float | None = None, ax: Any = None,
                history_mean: np.ndarray | None = None, label: str = "PSO") -> Any:
    """PSO length per iteration as the gap to the exact optimum in percent, log scale.

    Without a (positive, finite) optimum the gap is taken to the final best
    length instead, and the axis says so. Gaps below 1e-6 % are drawn at 1e-6 %.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(6, 3.2))
    else:
        fig = ax.figure
    best = np.asarray(history_best, dtype=float)
    exact = optimum is not None and bool(np.isfinite(optimum)) and optimum > 0
    ref = optimum if optimum is not None and exact else (float(best[-1]) if len(best) else 1.0)
    floor = 1e-6
    it = np.arange(1, len(best) + 1)
    ax.semilogy(it, np.maximum(100.0 * (best / ref - 1.0), floor), color="tab:red",
                label=f"{label} best")
    if history_mean is not None and len(history_mean):
        ax.semilogy(it, np.maximum(100.0 * (np.asarray(history_mean) / ref - 1.0), floor),
                    color="tab:red", ls=":", alpha=0.7, label=f"{label} swarm mean")
    ax.set_xlabel("iteration")
    ax.set_ylabel(("gap to optimum [%]" if exact else "gap to final best [%]")
                  + f" (floor {floor:g})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def planner_figure(world: PolygonWorld, results: Mapping[str, PlanResult], *,
                   optimum: float | None = None, graph: MaklinkGraph | None = None,
                   title: str = "") -> Any:
    """The map with every path and, when a result has a PSO history, its convergence.

    Returns the matplotlib Figure (one panel without a history: no empty panels).
    """
    import matplotlib.pyplot as plt

    histories = [(name, r) for name, r in results.items()
                 if r.history is not None and r.history.generations > 0]
    if histories:
        fig, (ax_map, ax_conv) = plt.subplots(
            1, 2, figsize=(11.5, 6.2), gridspec_kw={"width_ratios": [1.0, 0.9]})
    else:
        fig, ax_map = plt.subplots(figsize=(6.2, 6.6))
    figure(world, graph=graph, results=results, title=title or world.name, ax=ax_map)
    if histories:
        name, res = histories[0]
        h = res.history
        assert h is not None
        convergence(h.best_cost, optimum, ax=ax_conv, history_mean=h.mean_cost, label=name)
        ax_conv.set_title(f"{name} convergence ({h.generations} iterations, "
                          f"seed {res.info.get('seed', '-')})")
    fig.tight_layout()
    return fig


def save(fig: Any, path: str | Path) -> None:
    """Write a figure (folder created if needed) and close it."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)


def _cmap() -> Any:
    import matplotlib

    return matplotlib.colormaps["tab20"]
