"""Grid planner benchmarks: the acceptance figures of issue 4.

Run from the project root:  .venv/bin/python benchmarks/grid.py [--json OUT] [--quick]

* 512x512 distance fields (octile, chamfer 3/4) after warm-up;
* the MDT on the six 14x9 maps: time per plan and length against the DT
  (its equality with brute-force line-of-sight Dijkstra is a unit test);
* the MDT's two fills on the six maps: the thesis' level-by-level fill
  against the exact Dijkstra fill (cells whose value differs, largest excess,
  path lengths from the map's start, times);
* the GA (improved default and the thesis' preset) over 20 seeds per map:
  successes, how many within 5 % of the MDT length, worst ratio, mean time;
* a GA generation sweep (the thesis: "100 generations suffice"): success and
  within-5 % counts after 10 ... 400 generations, for both presets;
* VFF / VFH outcomes on the six maps and the trap;
* every row of every MovingAI scenario file, plain (early-stopped) and
  focused octile transforms: mismatches, max |error|, seconds;
* the six-map comparison table (thesis Tables 4.2-4.7).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MOVINGAI = ROOT.parent / "shared" / "data" / "movingai"


def _timed(fn, repeats):
    fn()  # warm-up (JIT)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times)


def field_times(out):
    from subtask_opt.planners.grid.distance_transform import distance_field
    from subtask_opt.planners.grid.world import GridWorld

    print("\n== 512x512 distance field (after warm-up), median / best of 7 ==")
    for name in ("random512-10-0", "8room_000"):
        world = GridWorld.from_movingai(MOVINGAI / "maps" / f"{name}.map")
        goal = tuple(int(v) for v in np.argwhere(~world.occupancy)[len(world.occupancy) // 2][::-1])
        for metric in ("octile", "chamfer34"):
            med, best = _timed(lambda w=world, g=goal, m=metric: distance_field(w, g, m), 7)
            print(f"{name:<16} {metric:<10} median {med * 1e3:7.1f} ms  best {best * 1e3:7.1f} ms")
            out.setdefault("field_512", []).append(
                {"map": name, "metric": metric, "median_s": med, "best_s": best})


def mdt_figures(out):
    from subtask_opt.planners.grid import distance_transform as dt
    from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case

    print("\n== MDT on the six 14x9 maps: time per plan (field + path), length vs DT, "
          "under each corner rule ==")
    nocut = dt.DTParams("chamfer34", corner_cutting=False)
    mdt_nocut = dt.MDTParams(corner_cutting=False)
    for name in THESIS_MAPS:
        c = thesis_case(name)
        med, best = _timed(lambda c=c: dt.plan_mdt(c.world, c.start, c.goal), 50)
        mdt_len = dt.plan_mdt(c.world, c.start, c.goal).length
        dt_len = dt.plan_dt(c.world, c.start, c.goal).length
        mdt_nocut_len = dt.plan_mdt(c.world, c.start, c.goal, params=mdt_nocut).length
        nocut_len = dt.plan_dt(c.world, c.start, c.goal, params=nocut).length
        print(f"{name:<10} median {med * 1e3:6.3f} ms  best {best * 1e3:6.3f} ms  "
              f"corner cutting: MDT {mdt_len:.3f} DT {dt_len:.3f}  "
              f"no cutting: MDT {mdt_nocut_len:.3f} DT {nocut_len:.3f}")
        out.setdefault("mdt", []).append({"map": name, "median_s": med, "best_s": best,
                                          "mdt_length": mdt_len, "dt_length": dt_len,
                                          "mdt_nocut_length": mdt_nocut_len,
                                          "dt_nocut_length": nocut_len})


def mdt_fill_figures(out):
    from subtask_opt.planners.grid import distance_transform as dt
    from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case

    print("\n== MDT fills: the thesis' level-by-level fill vs exact Dijkstra ==")
    print("value: the field at the map's start; path: the length walked (exact: down the\n"
          "field; levels: the thesis' step 5, to the visible cell of least value)")
    print(f"{'map':<10} {'cells':>5} {'differ':>6} {'max excess':>10} {'exact':>8} "
          f"{'lvl value':>9} {'lvl path':>8} {'exact ms':>8} {'level ms':>8}")
    for name in THESIS_MAPS:
        c = thesis_case(name)
        exact = dt.distance_field(c.world, c.goal, "anyangle", fill="exact")
        levels = dt.distance_field(c.world, c.goal, "anyangle", fill="levels")
        ok = np.isfinite(exact)
        excess = levels[ok] - exact[ok]
        differ = int(np.count_nonzero(excess > 1e-9))
        r_exact = dt.plan_mdt(c.world, c.start, c.goal)
        r_levels = dt.plan_mdt(c.world, c.start, c.goal, params=dt.MDTParams("levels"))
        t_exact, _ = _timed(lambda c=c: dt.plan_mdt(c.world, c.start, c.goal), 20)
        t_levels, _ = _timed(lambda c=c: dt.plan_mdt(c.world, c.start, c.goal,
                                                      params=dt.MDTParams("levels")), 20)
        lvl_value = r_levels.info["field_value"]
        print(f"{name:<10} {int(ok.sum()):>5} {differ:>6} {float(excess.max()):>10.4f} "
              f"{r_exact.length:>8.4f} {lvl_value:>9.4f} {r_levels.length:>8.4f} "
              f"{t_exact * 1e3:>8.3f} {t_levels * 1e3:>8.3f}")
        out.setdefault("mdt_fill", []).append({
            "map": name, "reachable_cells": int(ok.sum()), "cells_differ": differ,
            "max_excess": float(excess.max()), "exact_path": r_exact.length,
            "levels_value_at_start": lvl_value,
            "levels_path": r_levels.length, "exact_s": t_exact, "levels_s": t_levels})


def ga_sweep(out, seeds):
    from subtask_opt.base.stop import MaxGenerations
    from subtask_opt.planners.grid import distance_transform as dt
    from subtask_opt.planners.grid import ga_path
    from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case

    gens = (10, 25, 50, 100, 200, 400)
    print(f"\n== GA generation sweep over {seeds} seeds x 6 maps: successes / within 5% of the "
          "MDT without corner cutting (the GA's rule) ==")
    print(f"{'preset':<9} " + " ".join(f"{g:>11}" for g in gens))
    for label, params in (("improved", ga_path.GAPathParams()),
                          ("paper", ga_path.GAPathParams.paper())):
        cells = []
        for g in gens:
            ok = near = 0
            for name in THESIS_MAPS:
                c = thesis_case(name)
                best = dt.plan_mdt(c.world, c.start, c.goal,
                                   params=dt.MDTParams(corner_cutting=False)).length
                for s in range(seeds):
                    r = ga_path.plan(c.world, c.start, c.goal, params=params, seed=s,
                                     stop=MaxGenerations(g))
                    ok += r.success
                    near += r.success and r.length <= 1.05 * best
            total = seeds * len(THESIS_MAPS)
            cells.append(f"{ok:>3}/{near:>3}/{total:<3}")
            out.setdefault("ga_sweep", []).append({"preset": label, "generations": g,
                                                   "success": ok, "within_5pct": near,
                                                   "runs": total})
        print(f"{label:<9} " + " ".join(f"{x:>11}" for x in cells))


def ga_figures(out, seeds):
    from subtask_opt.planners.grid import distance_transform as dt
    from subtask_opt.planners.grid import ga_path
    from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case

    print(f"\n== GA over {seeds} seeds: successes / within 5% of the MDT without corner cutting "
          "/ worst ratio / mean time ==")
    c0 = thesis_case("open")
    ga_path.plan(c0.world, c0.start, c0.goal, seed=0)  # warm-up
    for label, params in (("improved", ga_path.GAPathParams()),
                          ("paper", ga_path.GAPathParams.paper())):
        for name in THESIS_MAPS:
            c = thesis_case(name)
            best = dt.plan_mdt(c.world, c.start, c.goal,
                               params=dt.MDTParams(corner_cutting=False)).length
            res = [ga_path.plan(c.world, c.start, c.goal, seed=s, params=params)
                   for s in range(seeds)]
            ok = sum(r.success for r in res)
            near = sum(r.success and r.length <= 1.05 * best for r in res)
            ratios = [r.length / best for r in res if r.success]
            worst = max(ratios) if ratios else float("inf")
            t = statistics.mean(r.runtime_s for r in res)
            print(f"{label:<9} {name:<10} success {ok:2d}/{seeds}  within 5%: {near:2d}/{seeds}  "
                  f"worst {worst:6.3f}  mean {t * 1e3:7.1f} ms")
            out.setdefault("ga", []).append({"preset": label, "map": name, "success": ok,
                                             "within_5pct": near, "seeds": seeds,
                                             "worst_ratio": worst, "mean_s": t})


def local_figures(out):
    from subtask_opt.planners.grid import vff, vfh
    from subtask_opt.planners.grid.maps import MAP_NAMES, thesis_case

    print("\n== VFF / VFH outcomes ==")
    for name in MAP_NAMES:
        c = thesis_case(name)
        for mod in (vff, vfh):
            r = mod.plan(c.world, c.start, c.goal)
            what = (f"reached, driven {r.info['driven_length']:.2f}" if r.success
                    else f"[{r.outcome}] {r.message}")
            print(f"{name:<10} {r.planner}: {what}")
            out.setdefault("local", []).append({"map": name, "planner": r.planner,
                                                "success": r.success,
                                                "outcome": str(r.outcome), "message": r.message})


def movingai_figures(out):
    from subtask_opt.planners.grid.movingai import bench, read_scenarios
    from subtask_opt.planners.grid.world import GridWorld

    print("\n== MovingAI: every row of every scenario file (octile DT vs optimum) ==")
    for scen_path in sorted((MOVINGAI / "scenarios").glob("*.scen")):
        name = scen_path.name.removesuffix(".map.scen")
        world = GridWorld.from_movingai(MOVINGAI / "maps" / f"{name}.map")
        scen = read_scenarios(scen_path)
        for focused in (False, True):
            rep = bench(world, scen, focused=focused)
            print(rep.summary())
            out.setdefault("movingai", []).append(rep.to_dict())


def table(out):
    from subtask_opt.planners.grid.compare import compare, format_table
    from subtask_opt.planners.grid.maps import THESIS_MAPS, thesis_case

    print("\n== six-map comparison (thesis Tables 4.2-4.7), best of 5 after warm-up ==")
    rows = []
    for name in THESIS_MAPS:
        c = thesis_case(name)
        rows.extend(compare(c.world, c.start, c.goal, repeats=5))
    print(format_table(rows))
    out["table"] = [r.to_dict() for r in rows]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="write all figures as JSON")
    ap.add_argument("--quick", action="store_true", help="skip the MovingAI full runs")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--sweep-seeds", type=int, default=10, help="seeds per map in the GA sweep")
    sections = {
        "fields": field_times, "mdt": mdt_figures, "mdt-fill": mdt_fill_figures,
        "ga": lambda o: ga_figures(o, args.seeds),
        "ga-sweep": lambda o: ga_sweep(o, args.sweep_seeds),
        "local": local_figures, "table": table, "movingai": movingai_figures,
    }
    ap.add_argument("--only", nargs="+", choices=list(sections), help="run these sections only")
    args = ap.parse_args()
    out: dict = {}
    for name, run in sections.items():
        if args.only and name not in args.only:
            continue
        if name == "movingai" and args.quick and not args.only:
            continue
        run(out)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
