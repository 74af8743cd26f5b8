"""Figures of the grid planners: maps, paths, distance fields."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
            "tab:pink", "tab:olive")


def plot_grid(world: Any, results: Sequence[Any] = (), *, start: Any = None, goal: Any = None,
              field: np.ndarray | None = None, ax: Any = None, title: str | None = None) -> Any:
    """Draw ``world`` (blocked cells dark), an optional distance ``field``
    underneath, and each :class:`PlanResult` path in ``results``; return the axes.

    Cell (x, y) is drawn centred on (x, y) with y growing downwards, as in
    the MovingAI convention. Failed results are listed in the legend only.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(max(4.0, world.width * 0.35), max(3.0, world.height * 0.35)))
    extent = (-0.5, world.width - 0.5, world.height - 0.5, -0.5)
    if field is not None:
        shown = np.where(np.isfinite(field), field, np.nan)
        im = ax.imshow(shown, cmap="viridis", extent=extent, interpolation="nearest")
        ax.figure.colorbar(im, ax=ax, fraction=0.03, label="distance to goal (cells)")
    ax.imshow(np.ma.masked_where(~world.occupancy, world.occupancy), cmap="Greys", vmin=0,
              vmax=1, extent=extent, interpolation="nearest")
    for i, res in enumerate(results):
        colour = _COLOURS[i % len(_COLOURS)]
        if res.success and len(res.path):
            p = np.asarray(res.path)
            ax.plot(p[:, 0], p[:, 1], "-o", color=colour, ms=3, lw=1.6,
                    label=f"{res.planner}: {res.length:.2f} cells, {res.turns} turns")
        else:
            short = res.message.split(" (")[0].split(" at ")[0].split(" after ")[0]
            ax.plot([], [], color=colour, label=f"{res.planner}: {short}")
            traj = res.info.get("trajectory") if hasattr(res, "info") else None
            if traj is not None and len(traj):
                t = np.asarray(traj)
                ax.plot(t[:, 0], t[:, 1], ":", color=colour, lw=1.2)
    if start is not None:
        ax.plot(*start, "s", color="green", ms=8, label="start")
    if goal is not None:
        ax.plot(*goal, "*", color="red", ms=12, label="goal")
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (cells)")
    ax.set_ylabel("y (cells)")
    if title or world.name:
        ax.set_title(title or world.name)
    if results or start is not None:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return ax


def save_grid_plot(path: str | Path, world: Any, results: Sequence[Any] = (),
                   **kwargs: Any) -> Path:
    """:func:`plot_grid` into a PNG file; return its path."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    ax = plot_grid(world, results, **kwargs)
    ax.figure.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(ax.figure)
    return path


def save_comparison_figure(path: str | Path, cases: Sequence[Any], rows: Sequence[Any]) -> Path:
    """The paths of every planner on each map (``bench grid --plot``), a 3 x 2 grid of maps."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 2, figsize=(15, 11))
    for ax, case in zip(axes.ravel(), cases, strict=False):
        results = [r.result for r in rows if r.map == case.name]
        plot_grid(case.world, results, start=case.start, goal=case.goal, ax=ax)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
