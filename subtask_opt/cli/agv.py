"""CLI commands of the AGV simulation: ``plan agv`` and ``bench agv``."""

from __future__ import annotations

import argparse

from subtask_opt.cli._common import (
    EXIT_OK,
    add_no_progress,
    add_outputs,
    add_workers,
    animation_output,
    failed,
    int_in,
    output_file,
    seed,
    where_text,
    workers_options,
)

MAX_FRAMES = 2_000
MAX_RUNS = 100_000

def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``plan agv`` and ``bench agv``."""
    p = plan.add_parser(
        "agv", help="simulate the AGV among moving obstacles (seed 004)",
        description="Run one AGV scenario: a paper experiment (1, 2-1, 2-2, 2-3), "
                    "'random' (built from --seed) or a JSON scenario file. Exit 1 when the "
                    "run ends in a collision, a timeout or without a path.")
    p.add_argument("--scenario", default="1", metavar="NAME|PATH",
                   help="1, 2-1, 2-2, 2-3, random, or a .json file (default: 1)")
    p.add_argument("--seed", type=seed, default=0,
                   help="seed of the random scenario and of the odometry drift (default: 0)")
    p.add_argument("--no-collision-check", action="store_true",
                   help="switch the t-second collision check off")
    p.add_argument("--drift", action="store_true",
                   help="odometry drift on (off in the paper's experiments)")
    p.add_argument("--no-check-points", action="store_true",
                   help="with --drift: no position fixes at corners")
    p.add_argument("--speed-up-to-pass", action="store_true",
                   help="speed up when the AGV enters a crossing first (default: keep speed)")
    add_outputs(p, what="the run (events, trajectory)", plot="a figure of the run")
    p.add_argument("--animate", metavar="OUT.gif", type=animation_output,
                   help="write a GIF of the run")
    p.add_argument("--frames", type=int_in(1, MAX_FRAMES), default=160, metavar="N",
                   help=f"at most N GIF frames, N in [1, {MAX_FRAMES}] (default: 160)")
    p.set_defaults(handler=_run_plan)

    b = bench.add_parser(
        "agv", help="random AGV suite: success, collisions, delay, drift error",
        description="Run N seeded random scenarios (1-5 obstacles crossing the route) with "
                    "odometry drift, with and without corner check points. Exit 1 when a "
                    "run (with check points) collides or times out.")
    b.add_argument("--n", type=int_in(1, MAX_RUNS), default=200, metavar="N",
                   help=f"number of runs, N in [1, {MAX_RUNS}] (default: 200)")
    b.add_argument("--seed", type=seed, default=0,
                   help="seed of the first run; run i uses seed + i (default: 0)")
    b.add_argument("--no-collision-check", action="store_true",
                   help="switch the t-second collision check off")
    b.add_argument("--no-drift", action="store_true", help="odometry drift off")
    add_workers(b, what="the runs")
    add_outputs(b, what="the totals", plot="a figure of the suite (outcomes, delay, drift)")
    add_no_progress(b)
    b.set_defaults(handler=_run_bench)


def _run_plan(args: argparse.Namespace) -> int:
    from subtask_opt.cli._common import refuse_overwriting_inputs, write_json
    from subtask_opt.planners.agv.scenarios import get_scenario
    from subtask_opt.planners.agv.simulation import simulate

    refuse_overwriting_inputs([args.scenario], [args.json, args.plot, args.animate])
    scenario = get_scenario(args.scenario, args.seed)
    scenario = scenario.with_params(
        collision_check=scenario.params.collision_check and not args.no_collision_check,
        drift=scenario.params.drift or args.drift,
        check_points=scenario.params.check_points and not args.no_check_points,
        speed_up_to_pass=scenario.params.speed_up_to_pass or args.speed_up_to_pass)
    run = simulate(scenario, seed=args.seed)
    print(run.summary())
    for e in run.events:
        print(f"  {e.time:7.2f} s  {e.kind:<11} {e.detail}")
    if args.json:
        write_json(args.json, run.to_dict())
    if args.plot or args.animate:
        from subtask_opt.plotting import agv as plots

        if args.plot:
            with output_file(args.plot) as tmp:
                plots.save_run_figure(run, tmp)
            print(f"figure written to {args.plot}")
        if args.animate:
            with output_file(args.animate) as tmp:
                plots.animate_run(run, tmp, max_frames=args.frames)
            print(f"animation written to {args.animate}")
    if not run.success:
        return failed(f"the AGV run ended in {run.outcome.value}")
    return EXIT_OK


def _run_bench(args: argparse.Namespace) -> int:
    from subtask_opt.cli._common import write_json
    from subtask_opt.planners.agv.scenarios import run_agv_suite, suite_params
    from subtask_opt.planners.agv.simulation import AgvParams

    base = AgvParams() if args.no_drift else suite_params()
    params = base if not args.no_collision_check else AgvParams(
        collision_check=False, drift=base.drift)
    import sys

    from subtask_opt.batch import suite_mapper, warm_agv

    where = workers_options(args)
    progress = not args.no_progress and sys.stderr.isatty()
    report = run_agv_suite(args.n, args.seed, params=params, progress=progress,
                           map_runs=suite_mapper(**where, progress=progress, desc="agv suite",
                                                 warm_up=warm_agv))
    print(f"{report.summary()} (on {where_text(where)})")
    if args.json:
        write_json(args.json, report.to_dict())
    if args.plot:
        from subtask_opt.plotting import agv as plots

        with output_file(args.plot) as tmp:
            plots.save_suite_figure(report, tmp)
        print(f"figure written to {args.plot}")
    if report.collisions + report.timeouts:
        return failed(f"{report.collisions} collisions and {report.timeouts} timeouts in "
                      f"{args.n} runs")
    return EXIT_OK
