"""Figure of a GTSPLIB tour: the vertices coloured by set, the tour through one of each."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from subtask_opt.tour.gtsplib import GtspInstance, GtspSolution


def plot_gtsp_tour(instance: GtspInstance, solution: GtspSolution, *,
                   ax: Axes | None = None) -> Axes:
    """Draw ``solution``'s closed tour over ``instance``'s coordinates (GEO: longitude
    across). Raises ValueError without coordinates."""
    import matplotlib.pyplot as plt

    if instance.coordinates is None:
        raise ValueError(f"{instance.name} has no vertex coordinates to draw")
    if ax is None:
        _, ax = plt.subplots(figsize=(7.5, 7.5))
    pts = np.asarray(instance.coordinates, dtype=float)
    if instance.edge_weight_type == "GEO":
        pts = pts[:, ::-1]
    tour = np.asarray(solution.tour, dtype=int)
    closed = np.append(tour, tour[0])
    big = len(pts) > 200
    ax.scatter(pts[:, 0], pts[:, 1], s=4 if big else 14, c=instance.sets % 20, cmap="tab20",
               zorder=2, label="vertices (colour: set)")
    ax.plot(pts[closed, 0], pts[closed, 1], "-", color="k", lw=0.8 if big else 1.2, zorder=3,
            label=f"tour, cost {solution.cost:g}")
    ax.scatter(pts[tour, 0], pts[tour, 1], s=10 if big else 30, color="k", zorder=4)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(f"{instance.name} ({instance.dimension} vertices, {instance.set_count} sets): "
                 f"cost {solution.cost:g}\nlower bound {solution.lower_bound:g}, seed "
                 f"{solution.seed}", fontsize=10)
    ax.legend(loc="best", fontsize=8, framealpha=0.85)
    return ax


def save_gtsp_figure(instance: GtspInstance, solution: GtspSolution, path: str | Path) -> Path:
    """Write :func:`plot_gtsp_tour` to ``path`` (PNG, PDF or SVG by extension)."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7.5, 7.5))
    try:
        plot_gtsp_tour(instance, solution, ax=ax)
        fig.tight_layout()
        fig.savefig(path, dpi=130)
    finally:
        plt.close(fig)
    return path
