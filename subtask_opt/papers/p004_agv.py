"""Seed paper 004 (AGV with a quadtree map among moving obstacles): experiments 1, 2-1..2-3.

The paper reports its experiments as figures (Figs. 3-6) and its set-up in
numbers (1 u/s for the AGV and the obstacles, 1 u = one 10 x 10-pixel cell of a
400 x 400 image, sonar 0.2-2 m, about 10 s before a stopped obstacle counts as
static). The maps are lost; the project's scenarios rebuild them. The random
suite (drift on, with and without corner check points: the self-location
module localising by sensed corners) is ours; the paper has no such table.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from subtask_opt.papers.report import Row

TITLE = "AGV on a quadtree map among moving obstacles"


def _event_time(run: Any, kind: str) -> float | None:
    return next((e.time for e in run.events if e.kind == kind), None)


def run(out: Path, *, quick: bool = False, seed: int = 0,
        map_runs: Any = None) -> tuple[list[Row], list[Path]]:
    """The four experiments and the suite (10 (quick) or 200 runs); figures into ``out``."""
    from subtask_opt.planners.agv.scenarios import PAPER_SCENARIOS, run_agv_suite
    from subtask_opt.planners.agv.simulation import simulate
    from subtask_opt.plotting import agv as plots

    rows: list[Row] = []
    files: list[Path] = []
    figs = {"1": "Fig. 3", "2-1": "Fig. 4", "2-2": "Fig. 5", "2-3": "Fig. 6"}
    runs = {}
    for name, make in PAPER_SCENARIOS.items():
        sc = make()
        r = simulate(sc)
        runs[name] = (sc, r)
        rows.append(Row(f"exp. {name} ({figs[name]}): the AGV reaches its goal", "success",
                        r.outcome.value, "",
                        f"rebuilt map; {r.time_s:.2f} s, delay {r.time_s - r.free_time_s:.2f} s"))
        path = out / f"004_experiment_{name}.png"
        plots.save_run_figure(r, path)
        files.append(path)

    sc1, r1 = runs["1"]
    rows.append(Row("§4.1: map cells (400 x 400 px image, 10 x 10 px cells)", 40 * 40,
                    int(r1.world.occupancy.size), "cells"))
    rows.append(Row("§4.2: AGV speed", 1.0, sc1.params.v_nominal, "u/s", "1 u = one cell"))
    speeds = sorted({o.speed for n in ("2-1", "2-2", "2-3") for o in runs[n][0].obstacles})
    rows.append(Row("§4.2: moving obstacles' speed", 1.0,
                    speeds[0] if len(speeds) == 1 else ", ".join(f"{v:g}" for v in speeds),
                    "u/s", "experiments 2-1, 2-2, 2-3"))
    rows.append(Row("§4.1: sonar range, nearest", 0.2, sc1.params.sonar_min_m, "m"))
    rows.append(Row("§4.1: sonar range, farthest", 2.0, sc1.params.sonar_max_m, "m"))
    _, r22 = runs["2-2"]
    crossing = next((e for e in r22.events if e.kind == "crossing"), None)
    rows.append(Row("exp. 2-2: the obstacle crosses the route while the AGV approaches",
                    "yes", "yes" if crossing is not None else "no", "",
                    f"event log: {crossing.time:.2f} s {crossing.detail}" if crossing else ""))
    wait, static = _event_time(r22, "wait"), _event_time(r22, "static")
    rows.append(Row("exp. 2-2: wait before a stopped obstacle counts as static", 10.0,
                    None if wait is None or static is None else round(static - wait, 2), "s",
                    "'about 10 s' in the paper"))
    rows.append(Row("exp. 2-2: re-plan around it and recover the route", "yes",
                    "yes" if _event_time(r22, "replan") is not None
                    and _event_time(r22, "recovery") is not None else "no"))

    n = 10 if quick else 200
    report = run_agv_suite(n, seed, map_runs=map_runs)
    note = "ours only (the paper has no suite)"
    rows.append(Row(f"suite of {n} random runs: successes with check points", None,
                    report.success, "runs", note))
    rows.append(Row(f"suite of {n}: successes without check points", None,
                    report.success_no_check, "runs", note))
    rows.append(Row(f"suite of {n}: mean drift error with / without check points", None,
                    f"{report.mean_drift_error:.3f} / {report.mean_drift_error_no_check:.3f}",
                    "", "cells; self-location by sensed corners (eq. 3)"))
    rows.append(Row(f"suite of {n}: collisions with moving obstacles or walls", None,
                    report.collisions, "runs", note))
    path = out / "004_suite.png"
    plots.save_suite_figure(report, path)
    files.append(path)
    return rows, files
