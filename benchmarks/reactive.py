"""Reactive navigation benchmarks (seed 001): the paper's three scenarios and the
random suite, fuzzy via-point selection (with and without the local-minimum
escape) beside the continuous VFF and VFH baselines.

    .venv/bin/python benchmarks/reactive.py [--n 200] [--seed 0] [--noise 0.0]
                                            [--json OUT] [--out DIR] [--figure PNG]
                                            [--workers N | --scheduler ADDRESS]

``--out DIR`` also writes, for each paper scenario and navigator, the
trajectory figure with the sonar beams and the per-step signals and (fuzzy
only) a GIF. ``--figure`` writes the overview of the paper scenarios (every
navigator's trajectory, e.g. docs/figures/reactive_navigation.png). Timings
exclude JIT compilation (one warm-up run first). The random suite runs here
by default; ``--workers N`` / ``--scheduler`` spread it as ``subtask-opt batch``
does (same table; the ms/run then share the cores).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from subtask_opt.batch import suite_mapper, warm_reactive
from subtask_opt.cli._common import add_workers, where_text, workers_options
from subtask_opt.planners.reactive.scenarios import PAPER_SCENARIOS, paper_scenario
from subtask_opt.planners.reactive.simulation import (
    NAVIGATORS,
    ReactiveParams,
    ReactiveRun,
    benchmark_navigators,
    simulate,
)
from subtask_opt.planners.reactive.sonar import SonarRing


def paper_runs(params: ReactiveParams, seed: int, out: Path | None
               ) -> tuple[list[dict], dict[str, tuple]]:
    """Every navigator on every paper scenario: summary rows and the runs by scenario."""
    rows = []
    by_scenario: dict[str, tuple] = {}
    for name in PAPER_SCENARIOS:
        sc = paper_scenario(name)
        runs: list[ReactiveRun] = []
        for nav in NAVIGATORS:
            run = simulate(sc.world, sc.start, sc.goal, nav, params=params, seed=seed)
            runs.append(run)
            rows.append(run.summary_dict())
            if out is not None:
                from subtask_opt.plotting.reactive import animate_run, save_run_figure

                save_run_figure(sc.world, run, out / f"{name}_{nav}.png")
                if nav == "fuzzy":
                    animate_run(sc.world, run, out / f"{name}_{nav}.gif", every=2)
        by_scenario[name] = (sc.world, runs)
    return rows, by_scenario


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--noise", type=float, default=0.0, help="sonar noise std")
    ap.add_argument("--json", help="write all figures as JSON")
    ap.add_argument("--out", help="folder for figures and GIFs")
    ap.add_argument("--figure", help="overview PNG of the paper scenarios")
    add_workers(ap, what="the random suite's runs", serial_default=True)
    args = ap.parse_args()
    where = workers_options(args)
    out = Path(args.out) if args.out else None
    if out is not None or args.figure:
        import matplotlib

        matplotlib.use("Agg")
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    params = ReactiveParams(sonar=SonarRing(noise_std=args.noise))

    t0 = time.perf_counter()
    benchmark_navigators(1, args.seed + 10_000, params=params)   # warm-up: JIT compilation
    print(f"warm-up (JIT) {time.perf_counter() - t0:.1f} s")

    print("\npaper scenarios")
    rows, by_scenario = paper_runs(params, args.seed, out)
    if args.figure:
        from subtask_opt.plotting.reactive import plot_paper_runs, save_figure

        fig = plot_paper_runs(by_scenario, title=(
            f"fuzzy via-point selection vs VFF and VFH on seed paper 001's scenarios "
            f"(18-beam sonar, noise {args.noise:g} m, seed {args.seed})"))
        print(f"figure: {save_figure(fig, args.figure)}")
    print(f"{'scenario':<10}{'navigator':<17}{'outcome':<10}{'steps':>6}{'path':>8}"
          f"{'min clear':>11}{'escape steps':>14}")
    for r in rows:
        print(f"{r['world']:<10}{r['navigator']:<17}{r['outcome']:<10}{r['steps']:>6}"
              f"{r['path_length']:>8.2f}{r['min_clearance']:>11.3f}{r['escape_steps']:>14}")

    t0 = time.perf_counter()
    table = benchmark_navigators(args.n, args.seed, params=params, progress=True,
                                 map_runs=suite_mapper(**where, progress=True, desc="reactive",
                                                       warm_up=warm_reactive))
    wall = time.perf_counter() - t0
    print(f"\nrandom suite: {args.n} scenarios, seed {args.seed}, noise {args.noise}, "
          f"{wall:.1f} s wall after warm-up on {where_text(where)}")
    print(f"{'navigator':<17}{'success':>9}{'coll.':>7}{'stall':>7}{'timeout':>9}{'rate':>8}"
          f"{'path ratio':>12}{'min clear':>11}{'ms/run':>9}")
    for name, row in table.items():
        print(f"{name:<17}{row['success']:>9}{row['collisions']:>7}{row['stalls']:>7}"
              f"{row['timeouts']:>9}"
              f"{row['success_rate']:>8.1%}{row['mean_path_ratio']:>12.3f}"
              f"{row['mean_min_clearance']:>11.3f}{row['mean_runtime_s'] * 1e3:>9.1f}")
    if args.json:
        Path(args.json).write_text(json.dumps(
            {"paper": rows, "suite": table, "n": args.n, "seed": args.seed,
             "noise": args.noise, "wall_time_s": wall}, indent=2, default=float) + "\n")


if __name__ == "__main__":
    main()
