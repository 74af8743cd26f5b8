"""Figures of the grid planners: maps, paths, distance fields, benchmark summaries.

Maps are drawn with ``imshow`` (one pixel per cell, never a patch per cell),
so a 512 x 512 MovingAI map draws as fast as a 14 x 9 one; figure sizes are
capped. Paths of several planners get their own colour, dash pattern and a
small sideways offset, so paths that share cells stay distinguishable.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
            "tab:pink", "tab:olive")
_DASHES = ("-", "--", "-.", (0, (5, 1, 1, 1)), (0, (3, 1, 1, 1, 1, 1)), (0, (8, 2)))
"""Line styles of successful paths; a failed drive is always dotted."""
MAX_FIGURE_INCHES = 10.0
"""The longer side of a single-map figure never exceeds this."""


def figure_size(width: int, height: int, *, per_cell: float = 0.35,
                cap: float = MAX_FIGURE_INCHES) -> tuple[float, float]:
    """(w, h) in inches for a ``width`` x ``height`` map: ``per_cell`` inches a
    cell, scaled down so that the longer side is at most ``cap``, and at least 3."""
    w, h = width * per_cell, height * per_cell
    scale = min(1.0, cap / max(w, h))
    return max(3.0, w * scale) + 2.5, max(3.0, h * scale)  # + room for the legend


def _offset(i: int, n: int, cells: float) -> float:
    """Sideways shift of path ``i`` of ``n`` (0 for a single path)."""
    if n <= 1:
        return 0.0
    return (i - (n - 1) / 2) * cells


def plot_grid(world: Any, results: Sequence[Any] = (), *, start: Any = None, goal: Any = None,
              field: np.ndarray | None = None, ax: Any = None, title: str | None = None,
              legend: bool = True) -> Any:
    """Draw ``world`` (blocked cells dark), an optional distance ``field``
    underneath, and each :class:`PlanResult` path in ``results``; return the axes.

    Cell (x, y) is drawn centred on (x, y) with y growing downwards, as in
    the MovingAI convention. Paths get distinct colours and dashes and, when
    there are several, a small sideways offset (at most 0.1 cell on small
    maps); a failed local planner's driven trajectory is drawn dotted and its
    reason is in the legend. The default title names the map and the planners.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=figure_size(world.width, world.height))
    extent = (-0.5, world.width - 0.5, world.height - 0.5, -0.5)
    if field is not None:
        shown = np.where(np.isfinite(field), field, np.nan)
        im = ax.imshow(shown, cmap="viridis", extent=extent, interpolation="nearest")
        ax.figure.colorbar(im, ax=ax, fraction=0.03, label="distance to goal (cells)")
    ax.imshow(np.ma.masked_where(~world.occupancy, world.occupancy), cmap="Greys", vmin=0,
              vmax=1, extent=extent, interpolation="nearest")
    big = max(world.width, world.height) > 64
    step = 0.0 if big else 0.06
    n = len(results)
    for i, res in enumerate(results):
        colour = _COLOURS[i % len(_COLOURS)]
        dash = _DASHES[i % len(_DASHES)]
        shift = _offset(i, n, step)
        if res.success and len(res.path):
            p = np.asarray(res.path, dtype=float) + shift
            ax.plot(p[:, 0], p[:, 1], linestyle=dash, marker=None if big else "o", color=colour,
                    ms=3, lw=1.4 if big else 1.8, alpha=0.9,
                    label=f"{res.planner}: {res.length:.2f} cells, {res.turns} turns")
        else:
            short = res.message.split(" at (")[0].split(" after ")[0].split(" (")[0]
            traj = res.info.get("trajectory") if hasattr(res, "info") else None
            if traj:
                t = np.asarray(traj, dtype=float) + shift
                ax.plot(t[:, 0], t[:, 1], ":", color=colour, lw=1.4,
                        label=f"{res.planner}: {short} (driven)")
                ax.plot(t[-1, 0], t[-1, 1], "x", color=colour, ms=8, mew=2)
            else:
                ax.plot([], [], linestyle=dash, color=colour, label=f"{res.planner}: {short}")
    if start is not None:
        ax.plot(*start, "s", color="green", ms=8 if not big else 6, label="start", zorder=5)
    if goal is not None:
        ax.plot(*goal, "*", color="red", ms=13 if not big else 10, label="goal", zorder=5)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (cells)")
    ax.set_ylabel("y (cells)")
    if title is None:
        names = ", ".join(dict.fromkeys(r.planner for r in results))
        title = f"{world.name or 'grid'} ({world.width}x{world.height})" + (
            f": {names}" if names else "")
    ax.set_title(title, fontsize=10)
    if legend and (results or start is not None):
        # right of the axes, past the colour bar when a distance field is drawn
        ax.legend(fontsize=7, loc="upper left",
                  bbox_to_anchor=(1.18 if field is not None else 1.01, 1.0))
    return ax


def _save(fig: Any, path: str | Path, dpi: int = 120) -> Path:
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return path


def save_grid_plot(path: str | Path, world: Any, results: Sequence[Any] = (),
                   **kwargs: Any) -> Path:
    """:func:`plot_grid` into a file (.png, .pdf, .svg); return its path."""
    ax = plot_grid(world, results, **kwargs)
    return _save(ax.figure, path)


def save_comparison_figure(path: str | Path, cases: Sequence[Any], rows: Sequence[Any]) -> Path:
    """The paths of every planner on each map (``bench grid --plot``), one panel a map."""
    import matplotlib.pyplot as plt

    n = len(cases)
    cols = 2 if n > 1 else 1
    nrows = (n + cols - 1) // cols
    fig, axes = plt.subplots(nrows, cols, figsize=(15, 3.7 * nrows), squeeze=False)
    for ax, case in zip(axes.ravel(), cases, strict=False):
        results = [r.result for r in rows if r.map == case.name]
        plot_grid(case.world, results, start=case.start, goal=case.goal, ax=ax)
    for ax in axes.ravel()[n:]:
        ax.remove()
    touch = list(dict.fromkeys(r.planner for r in rows if r.corner_cutting))
    closed = list(dict.fromkeys(r.planner for r in rows if not r.corner_cutting))
    rules = "; ".join(part for part in (
        f"{', '.join(touch)}: a move may touch a blocked corner (thesis)" if touch else "",
        f"{', '.join(closed)}: no move touches a blocked cell" if closed else "") if part)
    fig.suptitle("grid planners on the six 14x9 maps (thesis Tables 4.2-4.7)"
                 + (f"\ncorner rules: {rules}" if rules else ""))
    fig.tight_layout()
    return _save(fig, path, dpi=110)


def save_movingai_figure(path: str | Path, world: Any, scenarios: Any, report: Any,
                         queries: int = 5) -> Path:
    """``bench movingai --plot``: the map with its ``queries`` longest queries
    (start, goal, dashed straight line) and ours vs the file's optimum per row."""
    import matplotlib.pyplot as plt

    fig, (ax_map, ax_err) = plt.subplots(1, 2, figsize=(13, 6),
                                         gridspec_kw={"width_ratios": [1.2, 1]})
    plot_grid(world, ax=ax_map, legend=False,
              title=f"{report.map} ({world.width}x{world.height}): {queries} longest queries")
    longest = np.argsort(scenarios.optimal)[::-1][:queries]
    for k, i in enumerate(longest):
        s, g = scenarios.start[i], scenarios.goal[i]
        colour = _COLOURS[k % len(_COLOURS)]
        ax_map.plot([s[0], g[0]], [s[1], g[1]], "--", color=colour, lw=1, alpha=0.7)
        ax_map.plot(*s, "o", color=colour, ms=6)
        ax_map.plot(*g, "*", color=colour, ms=10,
                    label=f"row {i + 1}: optimum {scenarios.optimal[i]:.2f}")
    ax_map.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.08), ncol=2)
    ok = np.isfinite(report.ours)
    ax_err.plot(report.optimal[ok], report.ours[ok], ".", ms=3, color="tab:blue",
                label=f"rows ({report.rows}; {report.mismatches} mismatches)")
    if (~ok).any():
        ax_err.plot(report.optimal[~ok], np.full((~ok).sum(), report.optimal.max()), "x",
                    color="tab:red", label="unreachable by ours")
    top = float(report.optimal.max()) if report.optimal.size else 1.0
    ax_err.plot([0, top], [0, top], "-", color="grey", lw=0.8, label="ours = optimum")
    ax_err.set_xlabel("optimal length from the .scen file (cells)")
    ax_err.set_ylabel("octile distance transform (cells)")
    ax_err.set_title(f"ours vs optimum: max |error| {report.max_abs_error:.1e} cells",
                     fontsize=10)
    ax_err.legend(fontsize=8, loc="upper left")
    ax_err.set_aspect("equal", adjustable="box")
    fig.tight_layout()
    return _save(fig, path)
