"""Figures of polygon worlds: obstacles, MAKLINK links and cells, the graph, paths.

``draw_*`` functions draw onto a given axes; :func:`figure` builds a whole
figure (the paper's Figs. 1-4 in one panel or several) and :func:`save`
writes one to a file.
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

_PATH_STYLES = {
    "dijkstra": dict(color="tab:orange", ls="--", lw=1.6),
    "improved_dijkstra": dict(color="tab:green", ls="-.", lw=1.6),
    "pso": dict(color="tab:red", ls="-", lw=2.0),
    "visibility": dict(color="black", ls=":", lw=1.8),
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
    segs = graph.links.reshape(-1, 2, 2)
    ax.add_collection(LineCollection(segs, colors="tab:blue", lw=0.9, zorder=1,
                                     label="free links"))


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
            draw_path(ax, res.path, label=f"{name} ({res.length:.2f})", **style)
    if results or graph is not None:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.07), ncol=3, fontsize=8,
                  frameon=False)
    ax.set_title(title or world.name)
    return fig


def convergence(history_best: np.ndarray, optimum: float | None = None, ax: Any = None) -> Any:
    """PSO best length per iteration, with the exact optimum as a reference line."""
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(6, 3.2))
    else:
        fig = ax.figure
    ax.plot(np.arange(1, len(history_best) + 1), history_best, color="tab:red", label="PSO best")
    if optimum is not None:
        ax.axhline(optimum, color="black", ls=":", label=f"optimum {optimum:.4f}")
    ax.set_xlabel("iteration")
    ax.set_ylabel("path length")
    ax.legend()
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
