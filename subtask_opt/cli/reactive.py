"""CLI commands for the reactive navigators: ``plan reactive`` and ``bench reactive``."""

from __future__ import annotations

import argparse
import math
import time
from typing import Any

from subtask_opt.cli._common import ensure_parent, point, point3, positive_int, write_json

_NAVIGATORS = ("fuzzy", "fuzzy-no-escape", "vff", "vfh")


def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``plan reactive`` and ``bench reactive``."""
    p = plan.add_parser(
        "reactive", help="simulate a sonar-guided robot (fuzzy via-point selection, VFF, VFH)",
        description="Drive a differential-drive robot with a ring of 18 range sensors from "
                    "START to GOAL in a polygon world and report the run.")
    p.add_argument("--world", required=True,
                   help="a scenario (simple, u-trap, corridor), a built-in polygon world, "
                        "or a world JSON file")
    p.add_argument("--start", type=point3, default=None, metavar="X,Y,HEADING",
                   help="start pose, heading in degrees (default: the scenario's)")
    p.add_argument("--goal", type=point, default=None, metavar="X,Y",
                   help="goal point (default: the scenario's)")
    p.add_argument("--navigator", choices=_NAVIGATORS, default="fuzzy")
    p.add_argument("--seed", type=int, default=0, help="seed of the sensor noise")
    p.add_argument("--noise", type=float, default=0.0, metavar="STD",
                   help="standard deviation of the sonar noise (default 0)")
    p.add_argument("--range", dest="max_range", type=float, default=None, metavar="R",
                   help="sonar range R_max (default 2.5)")
    p.add_argument("--max-speed", type=float, default=None, help="speed limit (default 0.3)")
    p.add_argument("--max-turn-rate", type=float, default=None,
                   help="turn-rate limit in rad/s (default 1.2)")
    p.add_argument("--max-steps", type=positive_int, default=None,
                   help="sampling periods before a timeout (default 1500)")
    p.add_argument("--json", metavar="OUT", help="write the full run record as JSON")
    p.add_argument("--plot", metavar="OUT.png", help="trajectory with beams + memberships")
    p.add_argument("--animate", metavar="OUT.gif", help="GIF of the run")
    p.set_defaults(handler=_run_plan)

    b = bench.add_parser(
        "reactive", help="fuzzy vs VFF vs VFH on seeded random cluttered worlds",
        description="Run every navigator on N random scenarios and print success, collisions, "
                    "timeouts, path ratio to the exact shortest path and clearance.")
    b.add_argument("--n", type=positive_int, default=200, help="number of scenarios")
    b.add_argument("--seed", type=int, default=0)
    b.add_argument("--navigators", nargs="+", choices=_NAVIGATORS,
                   default=list(_NAVIGATORS))
    b.add_argument("--json", metavar="OUT", help="write the table as JSON")
    b.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    b.set_defaults(handler=_run_bench)


def _robot_and_sonar(args: argparse.Namespace) -> tuple[Any, Any]:
    """The robot and sonar of the command line (validated by their dataclasses)."""
    from subtask_opt.planners.reactive.sonar import SonarRing
    from subtask_opt.planners.reactive.unicycle import Unicycle

    robot_kw = {k: v for k, v in (("max_speed", args.max_speed),
                                  ("max_turn_rate", args.max_turn_rate)) if v is not None}
    sonar_kw = {"noise_std": args.noise}
    if args.max_range is not None:
        sonar_kw["max_range"] = args.max_range
    return Unicycle(**robot_kw), SonarRing(**sonar_kw)


def _run_plan(args: argparse.Namespace) -> int:
    from subtask_opt.base.errors import InputDataError
    from subtask_opt.planners.reactive.scenarios import resolve_world
    from subtask_opt.planners.reactive.simulation import SimParams, simulate

    world, scenario = resolve_world(args.world)
    if scenario is None and (args.start is None or args.goal is None):
        raise InputDataError(f"world {args.world!r} has no default start and goal: "
                             "give --start X,Y,HEADING and --goal X,Y")
    start = scenario.start if args.start is None else (
        args.start[0], args.start[1], math.radians(args.start[2]))
    goal = scenario.goal if args.goal is None else args.goal
    robot, sonar = _robot_and_sonar(args)
    params = SimParams() if args.max_steps is None else SimParams(max_steps=args.max_steps)
    run = simulate(world, start, goal, args.navigator, robot=robot, sonar=sonar,
                   params=params, seed=args.seed)
    print(run.summary())
    if args.json:
        write_json(args.json, run.to_dict())
    if args.plot or args.animate:
        from subtask_opt.plotting import reactive as rplot

        if args.plot:
            rplot.save_run_figure(world, run, ensure_parent(args.plot))
        if args.animate:
            rplot.animate_run(world, run, args.animate, every=2, progress=True)
    return 0


def _run_bench(args: argparse.Namespace) -> int:
    from subtask_opt.planners.reactive.simulation import benchmark

    t0 = time.perf_counter()
    table = benchmark(args.n, args.seed, navigators=args.navigators,
                      progress=not args.no_progress)
    wall = time.perf_counter() - t0
    head = (f"{'navigator':<16}{'runs':>6}{'success':>9}{'coll.':>7}{'timeout':>9}"
            f"{'rate':>8}{'path ratio':>12}{'min clear':>11}")
    print(f"bench reactive: {args.n} random scenarios, seed {args.seed}")
    print(head)
    for name, row in table.items():
        print(f"{name:<16}{row['runs']:>6}{row['success']:>9}{row['collisions']:>7}"
              f"{row['timeouts']:>9}{row['success_rate']:>8.1%}{row['mean_path_ratio']:>12.3f}"
              f"{row['mean_min_clearance']:>11.3f}")
    print(f"wall time {wall:.1f} s")
    if args.json:
        write_json(args.json, {"n": args.n, "seed": args.seed, "wall_time_s": wall,
                               "navigators": table})
    return 0

