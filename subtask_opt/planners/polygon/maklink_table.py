"""The comparison table of seed paper 003 (its Table 1), with the exact optimum beside it.

For each start/goal pair: Dijkstra over the MAKLINK graph, improved Dijkstra,
improved Dijkstra + PSO (mean, best and worst over several seeds), whether the
Dijkstra route passes every obstacle on the same side as the optimal path
(otherwise no sliding of its crossing points can reach the optimum), and the
exact optimum from the visibility graph.

The paper does not state its start and goal. ``benchmarks/maklink.py
--search`` fitted a set-up to its figures (Dijkstra 507.6910, improved
472.5326, PSO 439.0011; ant colony system 439.372), matched within 0.04 %:
world ``seed003-listed`` (the first obstacle in its listed, self-crossing
vertex order) and :data:`PAPER_PAIR`. A fit, not a reproduction: the paper's
own start and goal remain unknown. On the convex-hull world no pair comes
within 2 %. :data:`SEED003_PAIRS` are this project's own choices.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError, require_int
from subtask_opt.base.results import PlanResult
from subtask_opt.base.stop import StoppingCriterion
from subtask_opt.planners.polygon import maklink, pso, visibility
from subtask_opt.planners.polygon.world import PolygonWorld, same_homotopy

#: Start/goal pairs of the ``bench maklink`` table on ``seed003`` (the paper states none):
#: the two corner-to-corner diagonals, a left-to-right crossing, and two pairs whose
#: Dijkstra route passes an obstacle on the other side than the optimal path.
SEED003_PAIRS: tuple[tuple[tuple[float, float], tuple[float, float]], ...] = (
    ((20.0, 20.0), (320.0, 320.0)),
    ((10.0, 340.0), (340.0, 10.0)),
    ((20.0, 200.0), (330.0, 200.0)),
    ((145.0, 290.0), (5.0, 130.0)),
    ((140.0, 5.0), (260.0, 300.0)),
)

#: The start/goal fitted by ``benchmarks/maklink.py --search`` on ``seed003-listed`` (1 m grid):
#: Dijkstra 507.53, improved 472.41, PSO = optimum 438.99 (all within 0.04 % of the paper).
PAPER_PAIR: tuple[tuple[float, float], tuple[float, float]] = ((349.0, 13.0), (37.0, 296.0))

#: The lengths the paper reports for its (unstated) start and goal.
PAPER_TABLE1 = {"dijkstra": 507.6910, "improved": 472.5326, "pso": 439.0011, "acs": 439.372}


def default_pairs(world: PolygonWorld) -> list[tuple[Any, Any]]:
    """The built-in pairs: :data:`SEED003_PAIRS` for ``seed003``, :data:`PAPER_PAIR` for
    ``seed003-listed``; other worlds have none (InputDataError)."""
    if world.name == "seed003":
        return list(SEED003_PAIRS)
    if world.name == "seed003-listed":
        return [PAPER_PAIR]
    raise InputDataError(f"world {world.name!r} has no built-in start/goal pairs; "
                         "give them with --pair X,Y X,Y")


def first_pair_results(world: PolygonWorld, pair: tuple[Any, Any], *,
                       params: pso.PSOParams | None = None, seed: int | None = 0,
                       stop: StoppingCriterion | list[StoppingCriterion] | None = None
                       ) -> tuple[dict[str, PlanResult], maklink.MaklinkGraph, float]:
    """The four paths of one pair (Dijkstra, improved, PSO, optimum), the MAKLINK graph
    and the optimal length: what the table's figure shows."""
    s, g = pair
    results = {
        "Dijkstra": maklink.dijkstra(world, s, g),
        "improved Dijkstra": maklink.improved_dijkstra(world, s, g),
        "PSO": pso.plan(world, s, g, params=params, seed=seed, stop=stop),
        "optimum (visibility)": visibility.plan(world, s, g),
    }
    return results, maklink.graph_for(world), results["optimum (visibility)"].length


def table_rows(world: PolygonWorld, pairs: Sequence[tuple[Any, Any]], *, runs: int = 10,
               seed: int = 0, params: pso.PSOParams | None = None,
               stop: StoppingCriterion | list[StoppingCriterion] | None = None,
               on_run: Callable[[], None] | None = None) -> list[dict[str, Any]]:
    """One row per pair (PSO run ``runs`` times with seeds seed, seed + 1, ...).

    ``on_run`` is called after every PSO run (for a progress bar).

    Raises:
        ParameterError: ``runs`` < 1 or no pairs.
        InputDataError, UnreachableError: a bad start or goal.
    """
    require_int("table_rows", "runs", runs, 1)
    if len(pairs) == 0:
        raise ParameterError("table_rows: pairs must hold at least one start/goal pair, got []")
    for k, (start, goal) in enumerate(pairs):  # every pair checked before any work
        world.check_point(f"pair {k + 1} start", start)
        world.check_point(f"pair {k + 1} goal", goal)
    rows = []
    for start, goal in pairs:
        opt = visibility.plan(world, start, goal)
        dij = maklink.dijkstra(world, start, goal)
        imp = maklink.improved_dijkstra(world, start, goal)
        lengths, times = [], []
        for k in range(runs):
            t0 = time.perf_counter()
            res = pso.plan(world, start, goal, params=params, seed=seed + k, stop=stop)
            times.append(time.perf_counter() - t0)
            lengths.append(res.length)
            if on_run is not None:
                on_run()
        lengths_arr = np.array(lengths)
        found = opt.success
        rows.append({
            "found": found,
            "start": [float(v) for v in np.asarray(start, dtype=float)],
            "goal": [float(v) for v in np.asarray(goal, dtype=float)],
            "dijkstra": dij.length,
            "improved": imp.length,
            "pso_mean": float(lengths_arr.mean()),
            "pso_best": float(lengths_arr.min()),
            "pso_worst": float(lengths_arr.max()),
            "optimum": opt.length,
            "pso_gap_pct": (float(100 * (lengths_arr.mean() / opt.length - 1))
                            if found and opt.length > 0 else (0.0 if found else None)),
            "same_sides": same_homotopy(world, dij.path, opt.path) if found else None,
            "pso_ms": 1e3 * float(np.median(times)),
            "runs": runs,
        })
    return rows


def _yes_no(flag: bool | None) -> str:
    return "-" if flag is None else ("yes" if flag else "NO")


def format_table(rows: list[dict[str, Any]], *, title: str = "") -> str:
    """The rows as a plain-text table, the exact optimum as the last column."""
    def pt(p: list[float]) -> str:
        return f"({p[0]:g}, {p[1]:g})"

    runs = rows[0]["runs"] if rows else 0
    head = (f"{'start':>12} {'goal':>12} {'Dijkstra':>10} {'improved':>10} "
            f"{'PSO mean':>10} {'PSO worst':>10} {'gap %':>7} {'same sides':>10} "
            f"{'optimum':>10}")
    lines = [title] if title else []
    lines += [head, "-" * len(head)]
    for r in rows:
        if not r["found"]:
            lines.append(f"{pt(r['start']):>12} {pt(r['goal']):>12} no collision-free path")
            continue
        gap = "-" if r["pso_gap_pct"] is None else f"{max(r['pso_gap_pct'], 0.0):.3f}"
        lines.append(
            f"{pt(r['start']):>12} {pt(r['goal']):>12} {r['dijkstra']:10.4f} "
            f"{r['improved']:10.4f} {r['pso_mean']:10.4f} {r['pso_worst']:10.4f} {gap:>7} "
            f"{_yes_no(r['same_sides']):>10} {r['optimum']:10.4f}")
    p = PAPER_TABLE1
    lines += [
        f"PSO over {runs} seeds. 'same sides': the Dijkstra route passes every obstacle on "
        "the side the optimal path does;",
        "when it does not, sliding its crossing points (PSO) cannot reach the optimum.",
        f"Paper (start and goal not stated): Dijkstra {p['dijkstra']:.4f}, improved "
        f"{p['improved']:.4f}, PSO {p['pso']:.4f}, ant colony system {p['acs']:.3f}.",
    ]
    return "\n".join(lines)
