"""Figure of a TSPLIB tour: the closed tour over the node coordinates."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from subtask_opt.tour.tsplib import TspInstance, TspSolution


def plot_tour(instance: TspInstance, solution: TspSolution, *, ax: Axes | None = None) -> Axes:
    """Draw ``solution``'s closed tour over ``instance``'s coordinates.

    GEO coordinates are (latitude, longitude) in TSPLIB's DDD.MM form; they are
    drawn with longitude across. Raises ValueError without coordinates.
    """
    import matplotlib.pyplot as plt

    if instance.coordinates is None:
        raise ValueError(f"{instance.name} has no node coordinates to draw")
    if ax is None:
        _, ax = plt.subplots(figsize=(7.5, 7.5))
    pts = np.asarray(instance.coordinates, dtype=float)
    if instance.edge_weight_type == "GEO":
        pts = pts[:, ::-1]
        xlabel, ylabel = "longitude [DDD.MM]", "latitude [DDD.MM]"
    else:
        xlabel, ylabel = "x [TSPLIB units]", "y [TSPLIB units]"
    n = len(pts)
    order = np.asarray(solution.order, dtype=int)
    closed = np.append(order, order[0])
    small = n > 200
    ax.plot(pts[closed, 0], pts[closed, 1], "-", color="tab:red", lw=0.8 if small else 1.3,
            zorder=2, label=f"tour, length {solution.length}")
    ax.scatter(pts[:, 0], pts[:, 1], s=4 if small else 18, color="k", zorder=3, label="cities")
    ax.scatter(pts[order[0], 0], pts[order[0], 1], s=80, facecolor="none",
               edgecolor="tab:green", lw=2, zorder=4, label="first city")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(f"{instance.name} ({n} cities, {instance.edge_weight_type}): micro-GA tour "
                 f"{solution.length}\nlower bound {solution.lower_bound:g}, at most "
                 f"{100 * solution.gap_bound:.2f}% above optimum, seed {solution.seed}",
                 fontsize=10)
    ax.legend(loc="best", fontsize=8, framealpha=0.85)
    return ax


def save_tour_figure(instance: TspInstance, solution: TspSolution, path: str | Path) -> Path:
    """Write :func:`plot_tour` to ``path`` (PNG, PDF or SVG by extension)."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7.5, 7.5))
    plot_tour(instance, solution, ax=ax)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
