"""Figures of a sequencing result: the tour over the workspace, convergence.

* :func:`plot_workspace` - the region the arm reaches *within its joint limits*
  (IK on a raster, not the annulus |L1 - L2| <= r <= L1 + L2), and its base;
* :func:`plot_tour` - the tour zoomed to the subtasks (the whole workspace in an
  inset), each leg drawn as the path the tip really follows: a straight line for
  a straight-line leg, the forward kinematics of the joint interpolation for a
  joint move (a curve), legs the arm cannot drive as promised marked, leg numbers
  placed where they do not collide (or the visiting order in a side table for
  large tours, :func:`plot_order_table`);
* :func:`plot_convergence` - the best and the mean tour time as their excess over
  the final best, on a log scale, with the restarts marked;
* :func:`solution_figure` / :func:`save_solution_figure` - tour + convergence
  (+ order table), titled with robot, model, N and the total time;
* :func:`optimal_tours_figure` / :func:`save_optimal_tours_figure` - several
  tours of one instance side by side (e.g. its optimal tours).

Everything is computed from public fields: ``result.order``, ``result.report``,
``result.history``, ``problem.subtasks``, ``problem.timing`` and the arm's IK/FK.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.kinematics import _kernels as _k

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from subtask_opt.arm.planar_problem import PlanarProblem
    from subtask_opt.kinematics.planar import Arm
    from subtask_opt.tour.solve import Result

# Tours with more subtasks than this list their order in a side table instead of
# numbering the legs on the map.
MAX_LABELLED_LEGS = 40
# Arm poses are drawn at the subtasks up to this many subtasks.
MAX_ARM_POSES = 12

_STYLE = {  # leg kind -> (colour, line style, legend label)
    "line": ("tab:blue", "-", "straight line"),
    "joint": ("tab:orange", "-", "joint move (tip path by FK)"),
    "elbow": ("tab:purple", "-.", "joint move, elbow change"),
}


MAX_RESTART_LINES = 40
"""Restarts drawn as full-height lines; more are drawn as ticks on the floor."""


def reachable_raster(arm: Arm, extent: tuple[float, float, float, float],
                     resolution: int = 360) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(X, Y, mask) on a raster of ``extent`` (xmin, xmax, ymin, ymax): mask is True where
    some elbow branch reaches the point within the joint limits (analytic IK)."""
    xs = np.linspace(extent[0], extent[1], resolution)
    ys = np.linspace(extent[2], extent[3], resolution)
    grid_x, grid_y = np.meshgrid(xs, ys)
    pts = np.ascontiguousarray(np.column_stack([grid_x.ravel(), grid_y.ravel()]))
    q, _ = _k.ik_batch(arm.kinematics, pts, True)
    mask = np.isfinite(q).all(axis=2).any(axis=1).reshape(grid_x.shape)
    return grid_x, grid_y, mask


def _full_extent(arm: Arm) -> tuple[float, float, float, float]:
    bx, by = arm.base_xy
    r = 1.04 * arm.r_max
    return (bx - r, bx + r, by - r, by + r)


def plot_workspace(ax: Axes, arm: Arm, *, extent: tuple[float, float, float, float] | None = None,
                   resolution: int = 360, alpha: float = 0.12, label: bool = True) -> None:
    """Shade the region ``arm`` reaches within its joint limits, outline it, mark the base.

    ``extent`` (xmin, xmax, ymin, ymax) is the rastered window (default: the whole
    reach). The outline is the true boundary: inside ``r_min`` nothing is reachable,
    and joint limits can cut away more (planar_2r reaches nothing closer than
    about 0.19 m, while |L1 - L2| = 0.05 m).
    """
    ext = _full_extent(arm) if extent is None else extent
    grid_x, grid_y, mask = reachable_raster(arm, ext, resolution)
    if mask.any():
        m = mask.astype(float)
        ax.contourf(grid_x, grid_y, m, levels=[0.5, 1.5], colors=["tab:blue"], alpha=alpha)
        ax.contour(grid_x, grid_y, m, levels=[0.5], colors=["tab:blue"], linewidths=0.7,
                   alpha=0.6)
        if label:
            ax.fill([], [], color="tab:blue", alpha=alpha,
                    label="reachable within joint limits")
    bx, by = arm.base_xy
    if ext[0] <= bx <= ext[1] and ext[2] <= by <= ext[3]:
        ax.plot([bx], [by], marker="s", color="k", ms=6, ls="none",
                label="base" if label else None)


@dataclass(frozen=True)
class _Leg:
    index: int
    start: int
    end: int
    kind: str
    xy: np.ndarray
    infeasible: bool


def _configurations(problem: PlanarProblem, configurations: Any) -> np.ndarray:
    if configurations is not None:
        return np.asarray(configurations, dtype=np.int64)
    return np.asarray(problem.timing.configurations, dtype=np.int64)


def _stops(order: np.ndarray, stops: Any) -> list[tuple[int, int]]:
    """The (from, to) subtasks of every leg: ``stops`` as given, else the closed tour."""
    if stops is not None:
        return [(int(a), int(b)) for a, b in stops]
    n = len(order)
    return [(int(order[k]), int(order[(k + 1) % n])) for k in range(n)]


def report_stops(result: Result) -> tuple[PlanarProblem, list[tuple[int, int]], int | None]:
    """The problem a planar result's report describes (with its home point, if any, as the
    last subtask), the (from, to) subtasks of every leg the arm drives (an open path has no
    return leg; a home starts and ends a tour), and the home's subtask index or None."""
    report = result.report
    problem = report.problem
    home = problem.size - 1 if any(leg.start < 0 or leg.end < 0 for leg in report.legs) \
        else None
    pairs = [(home if leg.start < 0 else leg.start, home if leg.end < 0 else leg.end)
             for leg in report.legs]
    return problem, pairs, home  # type: ignore[return-value]


def tour_legs(problem: PlanarProblem, order: Any, configurations: Any = None,
              samples: int = 48, *, stops: Any = None) -> list[Any]:
    """The legs of the tour as the arm drives them under the problem's time model: the
    closed tour through ``order``, or the legs ``stops`` lists ((from, to) subtasks, e.g.
    an open path or a tour from a home, :func:`report_stops`).

    Each leg has ``index``, ``start``, ``end`` (subtasks), ``kind`` (``line``,
    ``joint`` or ``elbow`` for a joint move that changes elbow branch), ``xy``
    ((samples, 2) tip path: straight for a line, FK of the linear joint
    interpolation for a joint move) and ``infeasible``: a straight line the arm
    cannot drive as the model promised (Cartesian models: outside the reachable
    region, past a joint limit or over a joint speed limit; ``line``: a line
    replaced by a joint move).
    """
    timing = problem.timing
    pts = problem.subtasks.points
    configs = _configurations(problem, configurations)
    order = np.asarray(order, dtype=np.int64)
    q_both = problem.arm.ik(pts)  # (N, 2 branches, 2)
    moves = timing.moves(configs)
    check = timing.leg_check
    pairs = _stops(order, stops)
    if moves is None and check is not None:  # the tour's legs only, not all pairs
        outside, ratio = check.legs(np.array([a for a, _ in pairs], dtype=np.int64),
                                    np.array([b for _, b in pairs], dtype=np.int64))
    s = np.linspace(0.0, 1.0, samples)[:, None]
    legs = []
    for k, (a, b) in enumerate(pairs):
        ca, cb = int(configs[a]), int(configs[b])
        straight = moves is None or int(moves[a, b]) == 1
        infeasible = False
        if moves is None and check is not None:
            infeasible = bool(outside[k] or ratio[k] > 1.0)
        elif problem.time_model == "line":
            infeasible = timing.line_failure(a, b, ca, cb) is not None
        if straight:
            xy = pts[a] + s * (pts[b] - pts[a])
            kind = "line"
        else:
            q = q_both[a, ca] + s * (q_both[b, cb] - q_both[a, ca])
            xy = _k.fk_batch(problem.arm.kinematics, np.ascontiguousarray(q))[:, :2]
            kind = "joint" if ca == cb else "elbow"
        legs.append(_Leg(k, a, b, kind, xy, infeasible))
    return legs


def _zoom(points: np.ndarray, paths: list[np.ndarray], margin: float = 0.08
          ) -> tuple[float, float, float, float]:
    allxy = np.vstack([points, *paths]) if paths else points
    lo = allxy.min(axis=0)
    hi = allxy.max(axis=0)
    span = float(max(hi[0] - lo[0], hi[1] - lo[1], 1e-3))
    pad = margin * span
    return (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)


def _place_labels(ax: Axes, legs: list[Any], points: np.ndarray,
                  extent: tuple[float, float, float, float]) -> None:
    """Leg numbers next to their legs, each where it is farthest from points and labels."""
    span = max(extent[1] - extent[0], extent[3] - extent[2])
    obstacles = [p for p in points]
    for leg in legs:
        obstacles.extend(leg.xy[[len(leg.xy) // 4, len(leg.xy) // 2, 3 * len(leg.xy) // 4]])
    placed: list[np.ndarray] = []
    for leg in legs:
        best, best_score = None, -1.0
        for frac in (0.5, 0.35, 0.65, 0.2, 0.8):
            m = int(frac * (len(leg.xy) - 1))
            tangent = leg.xy[min(m + 1, len(leg.xy) - 1)] - leg.xy[max(m - 1, 0)]
            norm = float(np.hypot(*tangent)) or 1.0
            normal = np.array([-tangent[1], tangent[0]]) / norm
            for side in (1.0, -1.0):
                for dist in (0.022, 0.04):
                    cand = leg.xy[m] + side * dist * span * normal
                    others = np.array(obstacles + placed)
                    score = float(np.min(np.hypot(*(others - cand).T)))
                    if placed:  # labels repel labels harder than they repel points
                        score = min(score, 0.6 * float(np.min(np.hypot(
                            *(np.array(placed) - cand).T))))
                    if score > best_score:
                        best, best_score = cand, score
        assert best is not None
        placed.append(best)
        colour = _STYLE[leg.kind][0]
        ax.text(best[0], best[1], str(leg.index + 1), fontsize=6.5, color=colour, ha="center",
                va="center", zorder=7,
                bbox=dict(boxstyle="round,pad=0.12", fc="white", ec="none", alpha=0.75))


def _draw_arrow(ax: Axes, xy: np.ndarray, colour: str) -> None:
    m = len(xy) // 2
    ax.annotate("", xy=xy[m + 1], xytext=xy[m - 1],
                arrowprops=dict(arrowstyle="-|>", color=colour, lw=0.9, mutation_scale=9),
                zorder=4)


def _inset(ax: Axes, problem: PlanarProblem, legs: list[Any],
           extent: tuple[float, float, float, float], sub: Axes | None = None) -> None:
    """The whole workspace, small: in ``sub``, or to the right of ``ax`` below its legend."""
    from matplotlib.patches import Rectangle

    pts = problem.subtasks.points
    if sub is None:
        sub = ax.inset_axes((1.03, 0.0, 0.42, 0.42))
    plot_workspace(sub, problem.arm, resolution=160, alpha=0.25, label=False)
    for leg in legs:
        sub.plot(leg.xy[:, 0], leg.xy[:, 1], color=_STYLE[leg.kind][0], lw=0.5)
    sub.scatter(pts[:, 0], pts[:, 1], s=2, color="k")
    sub.add_patch(Rectangle((extent[0], extent[2]), extent[1] - extent[0],
                            extent[3] - extent[2], fill=False, ec="k", lw=0.8))
    sub.set_aspect("equal")
    sub.set_xticks([])
    sub.set_yticks([])
    sub.set_title("whole workspace (box: the view)", fontsize=7, pad=2)
    sub.set_facecolor("white")


def plot_tour(problem: PlanarProblem, order: Any, *, ax: Axes | None = None,
              title: str | None = None, draw_arm: bool = True,
              configurations: Any = None, label_legs: bool | None = None,
              inset: bool | Axes = True, stops: Any = None, home: int | None = None) -> Axes:
    """Draw the tour over the subtasks, zoomed to them, as the arm drives it: the closed
    tour through ``order``, or the legs ``stops`` lists (an open path, a tour from a home:
    :func:`report_stops`), ``home`` the subtask that is the home point (drawn as one).

    Args:
        problem: gives the points, the arm and the time model.
        order: the tour (any permutation, e.g. ``result.order``, or the input
            order as the "initial tour").
        ax: axes to draw into (a new figure if None).
        title: the axes title (default: robot, model, N and the tour time).
        draw_arm: draw the arm at every subtask (only up to ``MAX_ARM_POSES`` subtasks).
        configurations: elbow branch per subtask (default: the time model's).
        label_legs: number the legs on the map (default: up to
            ``MAX_LABELLED_LEGS`` subtasks; use :func:`plot_order_table` beyond).
        inset: show the whole workspace: True (when the view is zoomed, to the
            right of ``ax`` below the legend), an Axes to draw it into, or False.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(7, 7))
    pts = problem.subtasks.points
    arm = problem.arm
    order = np.asarray(order, dtype=np.int64)
    configs = _configurations(problem, configurations)
    legs = tour_legs(problem, order, configs, stops=stops)
    first = legs[0].start if legs else int(order[0])
    extent = _zoom(pts, [leg.xy for leg in legs])
    plot_workspace(ax, arm, extent=extent)
    if draw_arm and len(pts) <= MAX_ARM_POSES:
        q_both = arm.ik(pts)
        for i in range(len(pts)):
            q = q_both[i, int(configs[i])]
            if np.all(np.isfinite(q)):
                joints = arm.link_points(q)
                ax.plot(joints[:, 0], joints[:, 1], "-", color="0.6", lw=0.7, alpha=0.5,
                        zorder=2)
        ax.plot([], [], "-", color="0.6", lw=0.7, label="arm at each subtask")
    used = set()
    for leg in legs:
        colour, style, _ = _STYLE[leg.kind]
        used.add(leg.kind)
        ax.plot(leg.xy[:, 0], leg.xy[:, 1], ls=style, color=colour, lw=1.4, alpha=0.9,
                zorder=3)
        _draw_arrow(ax, leg.xy, colour)
        if leg.infeasible:
            mid = leg.xy[len(leg.xy) // 2]
            ax.plot(leg.xy[:, 0], leg.xy[:, 1], ls=(0, (2, 2)), color="tab:red", lw=2.2,
                    alpha=0.8, zorder=3.5)
            ax.plot([mid[0]], [mid[1]], marker="x", color="tab:red", ms=8, mew=2, zorder=4)
    for kind in ("line", "joint", "elbow"):
        if kind in used:
            colour, style, text = _STYLE[kind]
            ax.plot([], [], ls=style, color=colour, lw=1.4, label=text)
    n_bad = sum(leg.infeasible for leg in legs)
    if n_bad:
        what = ("straight line replaced by a joint move" if problem.time_model == "line"
                else "straight line the arm cannot drive as timed")
        ax.plot([], [], ls=(0, (2, 2)), color="tab:red", lw=2.2, marker="x",
                label=f"{what} ({n_bad})")
    visited = np.ones(len(pts), dtype=bool)
    if home is not None:
        visited[home] = False
        ax.scatter(pts[home, 0], pts[home, 1], s=90, marker="s", color="tab:purple",
                   zorder=6, label="home")
    ax.scatter(pts[visited, 0], pts[visited, 1], s=16 if len(pts) > 60 else 24, color="k",
               zorder=5, label="subtask")
    if first != home:
        ax.scatter(pts[first, 0], pts[first, 1], s=110, facecolor="none",
                   edgecolor="tab:green", lw=2, zorder=6, label="first subtask")
    if stops is not None and legs and legs[-1].end != first:
        last = legs[-1].end
        ax.scatter(pts[last, 0], pts[last, 1], s=110, marker="D", facecolor="none",
                   edgecolor="tab:red", lw=1.6, zorder=6, label="last subtask (open path)")
    if label_legs is None:
        label_legs = len(pts) <= MAX_LABELLED_LEGS
    if label_legs:
        _place_labels(ax, legs, pts, extent)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if title is None:
        title = f"{arm.name}, {problem.time_model} model, N = {int(visited.sum())}"
        if stops is None:
            title += f": {problem.tour_time(order):.3f} s"
    ax.set_title(title, fontsize=10)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7.5, frameon=False)
    zoomed = (extent[1] - extent[0]) < 1.5 * arm.r_max
    if inset is True and zoomed:
        _inset(ax, problem, legs, extent)
    elif inset is not True and inset is not False:  # an Axes: always drawn
        _inset(ax, problem, legs, extent, inset)
    return ax


def plot_order_table(ax: Axes, order: Any, *, columns: int | None = None) -> Axes:
    """The visiting order as a table of ``visit: subtask`` entries (for large tours)."""
    order = np.asarray(order, dtype=np.int64)
    n = len(order)
    columns = columns or max(1, int(np.ceil(n / 25)))
    rows = int(np.ceil(n / columns))
    ax.axis("off")
    for k, i in enumerate(order):
        c, r = divmod(k, rows)
        ax.text(c / columns, 1.0 - (r + 1) / (rows + 1), f"{k + 1:>3}: {int(i)}",
                transform=ax.transAxes, fontsize=7, family="monospace", va="center")
    ax.set_title("visiting order (leg k: from visit k to k+1)\nvisit: subtask index", fontsize=8)
    return ax


def plot_convergence(result: Result, *, ax: Axes | None = None,
                     optimum: float | None = None) -> Axes:
    """Best and population-mean tour time per generation, as excess over the final best.

    The excess (s) is drawn on a log scale, so that the late small improvements
    stay visible; generations at which the population was re-seeded are marked.
    ``optimum`` (e.g. a certified optimum) is drawn as its excess, if positive.
    """
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4))
    h = result.history
    final = float(h.best_cost[-1]) if h.generations else float(result.total_time)
    gens = np.arange(0, h.generations + 1)
    best = np.concatenate([[h.initial_best], h.best_cost])
    tiny = 1e-9 * abs(final)  # round-off between equal tours counts as no excess
    excess_best = np.where(best - final > tiny, best - final, 0.0)
    excess_mean = np.where(np.asarray(h.mean_cost) - final > tiny,
                           np.asarray(h.mean_cost) - final, 0.0)
    positive = np.concatenate([excess_best[excess_best > 0], excess_mean[excess_mean > 0]])
    floor = float(positive.min()) / 3 if positive.size else max(1e-6 * final, 1e-12)
    ax.plot(gens[1:], np.maximum(excess_mean, floor), color="0.6", lw=0.8,
            label="population mean")
    ax.step(gens, np.maximum(excess_best, floor), where="post", color="tab:blue", lw=1.6,
            label="best so far")
    ax.axhline(floor, color="0.5", ls=":", lw=0.8, label="excess 0 (drawn at this floor)")
    g_best = h.generation_of_best()
    ax.plot([g_best], [floor], marker="*", color="tab:green", ms=11, ls="none", zorder=5,
            label=f"final best reached (generation {g_best})")
    if len(h.restarts) <= MAX_RESTART_LINES:
        for i, g in enumerate(h.restarts):
            ax.axvline(g, color="tab:orange", lw=0.6, alpha=0.5,
                       label="restart" if i == 0 else None)
    elif len(h.restarts):  # too many to draw as lines: a tick per restart along the bottom
        ax.plot(h.restarts, np.full(len(h.restarts), floor), marker="|", ms=7, ls="none",
                color="tab:orange", alpha=0.4, label=f"restarts ({len(h.restarts)})")
    if optimum is not None and optimum < final:
        ax.axhline(final - optimum, color="tab:red", ls="--", lw=1,
                   label=f"gap to the optimum ({final - optimum:.3g} s)")
    ax.set_yscale("log")
    ax.set_xlabel("generation")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel("tour time - final best [s]")
    ax.set_title(f"convergence to {final:.4f} s ({result.preset} preset)\n"
                 f"{result.generations} generations, {result.restarts} restarts"
                 + (f" in {result.runs} runs" if result.runs > 1 else ""), fontsize=10)
    ax.legend(fontsize=7.5)
    return ax


def solution_figure(result: Result, problem: PlanarProblem) -> Figure:
    """The optimised tour, the convergence and (for large tours) the visiting order."""
    import matplotlib.pyplot as plt

    n = problem.size
    configs = result.report.configurations if result.report is not None else None
    stops: list[tuple[int, int]] | None = None
    home = None
    drawn = problem
    if result.report is not None and (result.constraints is not None and (
            result.constraints.tour == "open" or result.constraints.home is not None)):
        drawn, stops, home = report_stops(result)
    table = n > MAX_LABELLED_LEGS
    pts = problem.subtasks.points
    zoom = _zoom(pts, [])
    zoomed = (zoom[1] - zoom[0]) < 1.5 * problem.arm.r_max
    fig = plt.figure(figsize=((19 if table else 17) if zoomed else (17 if table else 15), 8))
    # columns: the tour, [its legend above the workspace overview,] convergence (+ order)
    ratios = (1.5, 0.55, 1.0) if zoomed else (1.5, 1.0)
    grid = fig.add_gridspec(2, len(ratios), width_ratios=ratios,
                            height_ratios=(1.0, 1.2) if table else (1.0, 1.0))
    tour_ax = fig.add_subplot(grid[:, 0])
    plot_tour(drawn, result.order, ax=tour_ax, configurations=configs,
              inset=fig.add_subplot(grid[1, 1]) if zoomed else False, stops=stops, home=home,
              title=None if stops is None else
              f"{problem.arm.name}, {problem.time_model} model, N = {n}: "
              f"{result.total_time:.3f} s")
    right = len(ratios) - 1
    plot_convergence(result, ax=fig.add_subplot(grid[0, right] if table else grid[:, right]))
    if table:
        plot_order_table(fig.add_subplot(grid[1, right]), result.order)
    shape = ("tour" if stops is None else "open path" if home is None
             else "tour from home" if result.constraints.tour == "closed"  # type: ignore[union-attr]
             else "open path from home")
    t0 = f" (input order {problem.tour_time(np.arange(n)):.3f} s)" if stops is None else ""
    fig.suptitle(f"{problem.arm.name}: {n} subtasks, {problem.time_model} time model - "
                 f"{shape} {result.total_time:.3f} s{t0}, seed {result.seed}", fontsize=12)
    fig.tight_layout()
    return fig


def save_solution_figure(result: Result, problem: PlanarProblem, path: str | Path) -> Path:
    """Write :func:`solution_figure` to ``path`` (PNG, PDF, SVG by extension)."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = solution_figure(result, problem)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def optimal_tours_figure(panels: Sequence[tuple[PlanarProblem, Any, str]], *,
                         title: str) -> Figure:
    """Tours side by side, one panel each: ``(problem, order, panel title)``.

    Made for several optimal tours of one instance (the sequencing paper's Figs. 8
    and 9); each panel is :func:`plot_tour` without arm poses or inset, legs numbered.
    """
    import matplotlib.pyplot as plt

    if not panels:
        raise ValueError("optimal_tours_figure needs at least one panel")
    fig, axes = plt.subplots(1, len(panels), figsize=(5.6 * len(panels), 5.8), squeeze=False)
    entries: dict[str, Any] = {}  # one legend for all panels, each entry once
    for ax, (problem, order, panel_title) in zip(axes[0], panels, strict=True):
        plot_tour(problem, order, ax=ax, title=panel_title, draw_arm=False, inset=False)
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            entries.setdefault(label, handle)
        legend = ax.get_legend()
        if legend is not None:
            legend.remove()
    fig.suptitle(title, fontsize=12)
    fig.tight_layout(rect=(0.0, 0.07, 1.0, 1.0))
    fig.legend(list(entries.values()), list(entries), loc="lower center", ncol=len(entries),
               fontsize=9, frameon=False)
    return fig


def save_optimal_tours_figure(panels: Sequence[tuple[PlanarProblem, Any, str]],
                              path: str | Path, *, title: str) -> Path:
    """Write :func:`optimal_tours_figure` to ``path`` (PNG, PDF, SVG by extension)."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = optimal_tours_figure(panels, title=title)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


__all__ = ["MAX_ARM_POSES", "MAX_LABELLED_LEGS", "optimal_tours_figure", "plot_convergence",
           "plot_order_table", "plot_tour", "plot_workspace", "reachable_raster",
           "save_optimal_tours_figure", "save_solution_figure", "solution_figure", "tour_legs"]
