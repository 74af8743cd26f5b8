"""CLI commands of the AGV simulation: ``plan agv`` and ``bench agv``."""

from __future__ import annotations

import argparse

from subtask_opt.cli._common import non_negative_int, positive_int


def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``plan agv`` and ``bench agv``."""
    p = plan.add_parser(
        "agv", help="simulate the AGV among moving obstacles (seed 004)",
        description="Run one AGV scenario: a paper experiment (1, 2-1, 2-2, 2-3), "
                    "'random' (built from --seed) or a JSON scenario file.")
    p.add_argument("--scenario", default="1", metavar="NAME|PATH",
                   help="1, 2-1, 2-2, 2-3, random, or a .json file (default: 1)")
    p.add_argument("--seed", type=non_negative_int, default=0,
                   help="seed of the random scenario (default: 0)")
    p.add_argument("--no-collision-check", action="store_true",
                   help="switch the t-second collision check off")
    p.add_argument("--json", metavar="OUT", help="write the run (events, trajectory) as JSON")
    p.add_argument("--animate", metavar="OUT.gif", help="write a GIF of the run")
    p.add_argument("--frames", type=positive_int, default=160,
                   help="at most this many GIF frames (default: 160)")
    p.add_argument("--plot", metavar="OUT.png", help="write a figure of the routes")
    p.set_defaults(handler=_run_plan)

    b = bench.add_parser(
        "agv", help="random AGV suite: success, collisions, delay",
        description="Run N seeded random scenarios (1-5 obstacles crossing the route).")
    b.add_argument("--n", type=positive_int, default=200, help="number of runs (default: 200)")
    b.add_argument("--seed", type=non_negative_int, default=0,
                   help="seed of the first run; run i uses seed + i (default: 0)")
    b.add_argument("--no-collision-check", action="store_true",
                   help="switch the t-second collision check off")
    b.add_argument("--json", metavar="OUT", help="write the totals as JSON")
    b.add_argument("--quiet", action="store_true", help="no progress bar")
    b.set_defaults(handler=_run_bench)


def _run_plan(args: argparse.Namespace) -> int:
    from subtask_opt.cli._common import write_json
    from subtask_opt.planners.agv.scenarios import get_scenario
    from subtask_opt.planners.agv.simulation import simulate

    scenario = get_scenario(args.scenario, args.seed)
    if args.no_collision_check:
        scenario = scenario.with_params(collision_check=False)
    run = simulate(scenario)
    print(run.summary())
    for e in run.events:
        print(f"  {e.time:7.2f} s  {e.kind:<9} {e.detail}")
    if args.json:
        write_json(args.json, run.to_dict())
    if args.plot or args.animate:
        from subtask_opt.plotting import agv as plots

        if args.plot:
            plots.save_run_figure(run, args.plot)
        if args.animate:
            plots.animate_run(run, args.animate, max_frames=args.frames)
            print(f"animation written to {args.animate}")
    return 0


def _run_bench(args: argparse.Namespace) -> int:
    from subtask_opt.cli._common import write_json
    from subtask_opt.planners.agv.scenarios import run_suite
    from subtask_opt.planners.agv.simulation import AgvParams

    params = AgvParams(collision_check=not args.no_collision_check)
    report = run_suite(args.n, args.seed, params=params, progress=not args.quiet)
    print(report.summary())
    if args.json:
        write_json(args.json, report.to_dict())
    return 0
