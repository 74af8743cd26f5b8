"""Seed paper 000 (the thesis): Fig. 2.4 value by value, Tables 4.2-4.7, the 100-generation claim.

The thesis' six maps (Figs. 4.1-4.6) did not survive, so Tables 4.2-4.7 run
on the project's rebuilt maps of rising difficulty
(:data:`~subtask_opt.planners.grid.maps.THESIS_MAPS`): lengths and turns can
only be compared in kind (MDT <= DT, the GA longest or failing on the hardest
map), not value for value. Fig. 2.4 survives and is compared cell by cell.

DT and MDT run with one corner rule, the thesis' own (Fig. 2.4: a move may touch a
blocked cell at a corner, never pass between two blocked cells touching there), so
the MDT is never longer than the DT; the GA planner keeps the closed-square rule
(no move touches a blocked cell). Every row's note names its rule.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.papers.report import Row

TITLE = "thesis: distance transforms, MDT and the GA path planner (grid)"

X = None
#: Fig. 2.4 as printed (3:4 units; None: an obstacle cell), rows y = 0..8 of the 14 x 9 space.
FIG_2_4 = (
    (37, 34, 31, 28, 25, 22, 19, 16, 13, 10, 7, 4, 3, 4),
    (38, X, X, X, X, 21, 18, 15, 12, 9, 6, 3, 0, 3),
    (41, X, X, X, X, 22, 19, 16, 13, 10, 7, 4, 3, 4),
    (40, X, X, X, X, 23, 20, 17, 14, 11, 8, 7, 6, 7),
    (39, 36, 33, 30, 27, 24, 21, 18, 15, 12, 11, 10, 9, 10),
    (40, 37, 34, 31, 28, 25, 22, 19, 16, X, X, X, X, X),
    (41, 38, 35, 32, 29, 26, 23, 20, 19, X, X, X, X, X),
    (42, 39, 36, 33, 30, 27, 24, 23, 22, X, X, X, X, X),
    (43, 40, 37, 34, 31, 28, 27, 26, 25, X, X, X, X, X),
)

#: Tables 4.2-4.7: (time in ms, length in cells, turns) of DT, MDT and GA per figure
#: (None: no path).
TABLES: dict[str, dict[str, tuple[float, float, int] | None]] = {
    "4.2": {"dt": (0.92, 14.89, 4), "mdt": (270.0, 14.29, 4), "ga": (490.0, 16.18, 3)},
    "4.3": {"dt": (0.92, 16.09, 6), "mdt": (220.0, 15.75, 2), "ga": (430.0, 16.0, 3)},
    "4.4": {"dt": (0.92, 16.72, 7), "mdt": (280.0, 16.29, 7), "ga": (490.0, 18.48, 4)},
    "4.5": {"dt": (0.93, 19.89, 6), "mdt": (170.0, 19.64, 6), "ga": (440.0, 21.37, 3)},
    "4.6": {"dt": (0.93, 20.31, 6), "mdt": (270.0, 19.96, 6), "ga": (600.0, 21.99, 3)},
    "4.7": {"dt": (0.94, 27.31, 12), "mdt": (270.0, 16.53, 9), "ga": None},
}
#: Table 4.1: the GA's parameters (population, generations, crossover and mutation rates).
TABLE_4_1 = {"population": 50, "generations": 100, "crossover rate": 0.6, "mutation rate": 0.2}

_PLANNERS = {"dt": "dt", "mdt": "mdt", "ga": "ga-paper"}
_NAMES = {"dt": "DT", "mdt": "MDT", "ga": "GA"}
#: The corner rules by :attr:`~subtask_opt.planners.grid.compare.CompareRow.corner_cutting`.
CORNER_RULES = {True: "thesis corner rule: a move may touch a blocked corner",
                False: "closed-square rule: no move touches a blocked cell"}


def fig_2_4_rows() -> tuple[list[Row], np.ndarray]:
    """Fig. 2.4 recomputed (3:4 transform with the thesis' corner cutting) against the print."""
    from subtask_opt.planners.grid import distance_transform as dt
    from subtask_opt.planners.grid.maps import thesis_case

    case = thesis_case("fig2.4")
    field = dt.distance_field(case.world, case.goal, "chamfer34", corner_cutting=True) * 3
    printed = [(y, x, v) for y, row in enumerate(FIG_2_4) for x, v in enumerate(row)
               if v is not None]
    diffs = [abs(float(field[y, x]) - v) for y, x, v in printed]
    equal = sum(d == 0 for d in diffs)
    return [
        Row("Fig. 2.4: free cells with a value", len(printed),
            int(np.isfinite(field).sum()), "cells", "14 x 9 work space, S (2,7), G (12,1)"),
        Row("Fig. 2.4: values equal to the print", len(printed), equal, "cells",
            f"3:4 transform; {CORNER_RULES[True]}"),
        Row("Fig. 2.4: largest |ours - print|", 0, max(diffs), "3:4 units"),
    ], field


def table_rows(seed: int) -> tuple[list[Row], list[Any], list[Any]]:
    """Tables 4.2-4.7 on the rebuilt maps (rows per algorithm and table: time, length, turns)."""
    from subtask_opt.planners.grid.compare import compare
    from subtask_opt.planners.grid.distance_transform import DTParams, MDTParams
    from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case

    thesis_rule = {"dt": DTParams("chamfer34", corner_cutting=True),
                   "mdt": MDTParams(corner_cutting=True)}
    rows: list[Row] = []
    cases: list[Any] = []
    results: list[Any] = []
    shorter = 0
    for (table, paper), name in zip(TABLES.items(), THESIS_MAPS, strict=True):
        case = thesis_case(name)
        cases.append(case)
        got = {r.planner: r for r in compare(case.world, case.start, case.goal,
                                             names=tuple(_PLANNERS.values()), seed=seed,
                                             repeats=1, params=thesis_rule)}
        results.extend(got.values())
        d, m = got["dt"], got["mdt"]
        shorter += bool(d.success and m.success and m.length <= d.length + 1e-9)
        for key, planner in _PLANNERS.items():
            r = got[planner]
            ref = paper[key]
            note = (f"rebuilt map {name!r}" + (", thesis GA preset" if key == "ga" else "")
                    + f"; {CORNER_RULES[r.corner_cutting]}")
            rows.append(Row(f"Table {table}: {_NAMES[key]} time",
                            "no path" if ref is None else ref[0],
                            round(1e3 * r.time_s, 3) if r.success else "no path", "ms",
                            note + "; this machine, after warm-up"))
            rows.append(Row(f"Table {table}: {_NAMES[key]} length",
                            "no path" if ref is None else ref[1],
                            round(r.length, 2) if r.success else "no path", "cells", note))
            rows.append(Row(f"Table {table}: {_NAMES[key]} turns",
                            "no path" if ref is None else ref[2],
                            r.turns if r.success else "no path", "", note))
    rows.append(Row("Tables 4.2-4.7: maps where the MDT is not longer than the DT",
                    len(TABLES), shorter, "maps", f"both under the {CORNER_RULES[True]}"))
    return rows, cases, results


def generation_rows(seed: int, seeds: int) -> list[Row]:
    """§4: "from 100 generations on the GA gives the same path": thesis GA at 100 vs 400."""
    from subtask_opt.base.stop import MaxGenerations
    from subtask_opt.planners.grid.compare import plan_grid
    from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case

    same = runs = 0
    for name in THESIS_MAPS:
        case = thesis_case(name)
        for s in range(seed, seed + seeds):
            a = plan_grid(case.world, case.start, case.goal, "ga-paper", seed=s,
                          stop=MaxGenerations(100))
            b = plan_grid(case.world, case.start, case.goal, "ga-paper", seed=s,
                          stop=MaxGenerations(400))
            runs += 1
            same += bool(a.success == b.success and (not a.success
                                                      or abs(a.length - b.length) < 1e-9))
    return [Row("§4: runs whose path at 100 generations equals that at 400", runs, same,
                "runs", f"thesis GA preset, 6 maps x {seeds} seeds (the thesis: all)")]


def run(out: Path, *, quick: bool = False, seed: int = 0,
        map_runs: Any = None) -> tuple[list[Row], list[Path]]:
    """Every numbered result of the thesis beside ours; figures into ``out``."""
    fig_rows, field = fig_2_4_rows()
    rows = list(fig_rows)
    from subtask_opt.planners.grid.ga_path import PAPER_STOP, GAPathParams

    preset = GAPathParams.paper()
    ours = {"population": preset.population, "crossover rate": preset.crossover_rate,
            "mutation rate": preset.mutation_rate,
            "generations": next(getattr(c, "generations", None) for c in PAPER_STOP)}
    rows += [Row(f"Table 4.1: GA {k}", v, ours[k], "", "planner ga-paper")
             for k, v in TABLE_4_1.items()]
    trows, cases, results = table_rows(seed)
    rows += trows
    rows += generation_rows(seed, 2 if quick else 10)

    from subtask_opt.planners.grid.maps import thesis_case
    from subtask_opt.plotting.grid import save_comparison_figure, save_grid_plot

    case = thesis_case("fig2.4")
    files = [save_grid_plot(out / "000_fig2.4_field.png", case.world, (), start=case.start,
                            goal=case.goal, field=field,
                            title="thesis Fig. 2.4 recomputed: 3:4 distance field "
                                  "(side 3, diagonal 4) to G (12,1)"),
             save_comparison_figure(out / "000_tables_4.2-4.7.png", cases, results)]
    return rows, files
