"""CLI commands of the reactive navigators.

``subtask-opt plan reactive``     one simulated run (exit 1 on collision, stall, timeout)
``subtask-opt bench reactive``    every navigator on seeded random cluttered worlds
``subtask-opt bench fuzzy-table`` seed paper 001's Table 1 recomputed beside the paper's numbers
"""

from __future__ import annotations

import argparse
import math

from subtask_opt.cli._common import (
    EXIT_FAILED,
    EXIT_OK,
    add_no_progress,
    add_outputs,
    add_workers,
    animation_output,
    ascii_float,
    ascii_number,
    failed,
    output_file,
    point,
    point3,
    positive_int,
    refuse_overwriting_inputs,
    seed,
    where_text,
    workers_options,
    write_json,
)


def _numbers(text: str) -> tuple[float, ...]:
    """Comma-separated finite numbers."""
    try:
        values = tuple(float(ascii_number(p)) for p in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}"
                                         ) from None
    if not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"values must be finite, got {text!r}")
    return values



def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``plan reactive``, ``bench reactive`` and ``bench fuzzy-table``."""
    from subtask_opt.planners.base import planners

    navigators = planners("reactive")
    listing = "; ".join(f"{name}: {info.description}" for name, info in navigators.items())

    p = plan.add_parser(
        "reactive", help="simulate a sonar-guided robot (fuzzy via-point selection, VFF, VFH)",
        description="Drive a differential-drive robot with a ring of range sensors from "
                    "START to GOAL in a polygon world and report the run. Exit 1 when the "
                    "run ends in a collision, a stall or a timeout.")
    p.add_argument("--world", required=True, metavar="NAME|PATH.json",
                   help="a scenario (simple, u-trap, corridor), a built-in polygon world, "
                        "a world JSON file or a scenario JSON file")
    p.add_argument("--start", type=point3, default=None, metavar="X,Y,HEADING",
                   help="start pose, heading in degrees (default: the scenario's)")
    p.add_argument("--goal", type=point, default=None, metavar="X,Y",
                   help="goal point (default: the scenario's)")
    p.add_argument("--navigator", choices=list(navigators), default="fuzzy", help=listing)
    p.add_argument("--seed", type=seed, default=0,
                   help="seed of the sensor noise, in [0, 2**63) (default 0)")
    _robot_options(p)
    add_outputs(p, what="the full run record",
                plot="the trajectory with sonar beams above the per-step signals")
    p.add_argument("--animate", metavar="OUT.gif", type=animation_output, help="GIF of the run")
    add_no_progress(p)
    p.set_defaults(handler=_run_plan)

    b = bench.add_parser(
        "reactive", help="fuzzy vs VFF vs VFH on seeded random cluttered worlds",
        description="Run every navigator on N random scenarios and print success, collisions, "
                    "stalls, timeouts, path ratio to the exact shortest path and clearance.")
    b.add_argument("--n", type=positive_int, default=200,
                   help="number of scenarios, at most 1000000 (default 200)")
    b.add_argument("--seed", type=seed, default=0, help="seed of the scenarios and the noise")
    b.add_argument("--navigators", nargs="+", choices=list(navigators),
                   default=list(navigators), help=listing)
    _robot_options(b)
    add_workers(b, what="the runs")
    add_outputs(b, what="the table", plot="a bar chart of the outcomes per navigator")
    add_no_progress(b)
    b.set_defaults(handler=_run_bench)

    t = bench.add_parser(
        "fuzzy-table", help="seed paper 001's Table 1: the fuzzy decision beside the paper",
        description="Recompute the decision memberships muD = min_j muGj^wj of the paper's "
                    "seven candidates (eq. 1, 7) and print them beside the paper's numbers. "
                    "Without weights (the paper's plain minimum) exit 1 unless they match.")
    group = t.add_mutually_exclusive_group()
    group.add_argument("--weights", type=_numbers, metavar="W1,W2,W3",
                       help="importance of G1, G2, G3 (each in (0, 100]; default 1,1,1)")
    group.add_argument("--pairwise", type=_numbers, metavar="A12,A13,A23",
                       help="Saaty pairwise comparisons of the goals (upper triangle); the "
                            "weights are the matrix's principal eigenvector")
    add_outputs(t, what="the table", plot="paper vs recomputed decision memberships")
    t.set_defaults(handler=_run_fuzzy_table)


def _robot_options(p: argparse.ArgumentParser) -> None:
    """Robot, sonar and run-length options (bounds are checked by the parameter classes)."""
    g = p.add_argument_group("robot and sonar")
    g.add_argument("--noise", type=ascii_float, default=0.0, metavar="STD",
                   help="standard deviation of the sonar noise, in [0, range] (default 0)")
    g.add_argument("--range", dest="max_range", type=ascii_float, default=None, metavar="R",
                   help="sonar range R_max in (0, 1e6] (default 2.5)")
    g.add_argument("--max-speed", type=ascii_float, default=None, metavar="V",
                   help="speed limit > 0, at most range / dt (default 0.3)")
    g.add_argument("--max-turn-rate", type=ascii_float, default=None, metavar="RAD_PER_S",
                   help="turn-rate limit in rad/s, in (0, pi / dt] (default 1.2)")
    g.add_argument("--dt", type=ascii_float, default=None, metavar="S",
                   help="sampling time in seconds > 0 (default 0.5)")
    g.add_argument("--max-steps", type=positive_int, default=None,
                   help="sampling periods before a timeout (default 1500; a run whose "
                        "record would need more than 1 GiB is refused)")


def _params(args: argparse.Namespace):  # noqa: ANN202 - imported lazily
    """The :class:`ReactiveParams` of the command line (validated by the dataclasses)."""
    from subtask_opt.planners.reactive.simulation import ReactiveParams, SimParams
    from subtask_opt.planners.reactive.sonar import SonarRing
    from subtask_opt.planners.reactive.unicycle import Unicycle

    robot_kw = {k: v for k, v in (("max_speed", args.max_speed),
                                  ("max_turn_rate", args.max_turn_rate),
                                  ("dt", args.dt)) if v is not None}
    sonar_kw = {"noise_std": args.noise}
    if args.max_range is not None:
        sonar_kw["max_range"] = args.max_range
    sim = SimParams() if args.max_steps is None else SimParams(max_steps=args.max_steps)
    return ReactiveParams(robot=Unicycle(**robot_kw), sonar=SonarRing(**sonar_kw), sim=sim)


def _run_plan(args: argparse.Namespace) -> int:
    from subtask_opt.base.errors import InputDataError
    from subtask_opt.planners.reactive.scenarios import resolve_world
    from subtask_opt.planners.reactive.simulation import simulate

    refuse_overwriting_inputs([args.world], [args.json, args.plot, args.animate])
    params = _params(args)
    world, scenario = resolve_world(args.world)
    if args.start is not None:
        start: tuple[float, ...] = (args.start[0], args.start[1], math.radians(args.start[2]))
    elif scenario is not None:
        start = scenario.start
    else:
        raise InputDataError(f"world {args.world!r} has no default start: give --start X,Y,HEADING")
    if args.goal is not None:
        goal: tuple[float, ...] = args.goal
    elif scenario is not None:
        goal = scenario.goal
    else:
        raise InputDataError(f"world {args.world!r} has no default goal: give --goal X,Y")
    run = simulate(world, start, goal, args.navigator, params=params, seed=args.seed)
    print(run.summary())
    if args.json:
        write_json(args.json, run.to_dict())
    if args.plot or args.animate:
        from subtask_opt.plotting import reactive as rplot

        if args.plot:
            with output_file(args.plot) as tmp:
                rplot.save_run_figure(world, run, tmp)
        if args.animate:
            with output_file(args.animate) as tmp:
                rplot.animate_run(world, run, tmp, every=2,
                                  progress=not args.no_progress)
    return EXIT_OK if run.success else failed(f"{run.outcome.value}: {run.message}")


def _run_bench(args: argparse.Namespace) -> int:
    import sys
    import time

    from subtask_opt.batch import suite_mapper, warm_reactive
    from subtask_opt.planners.reactive.simulation import benchmark_navigators

    params = _params(args)
    where = workers_options(args)
    progress = not args.no_progress and sys.stderr.isatty()
    t0 = time.perf_counter()
    table = benchmark_navigators(args.n, args.seed, navigators=args.navigators, params=params,
                                 progress=progress,
                                 map_runs=suite_mapper(**where, progress=progress,
                                                       desc="reactive", warm_up=warm_reactive))
    wall = time.perf_counter() - t0
    print(f"bench reactive: {args.n} random scenarios, seed {args.seed}, "
          f"sonar noise {args.noise:g}, on {where_text(where)}")
    print(f"{'navigator':<16}{'runs':>6}{'success':>9}{'coll.':>7}{'stall':>7}{'timeout':>9}"
          f"{'rate':>8}{'path ratio':>12}{'min clear':>11}")
    for name, row in table.items():
        print(f"{name:<16}{row['runs']:>6}{row['success']:>9}{row['collisions']:>7}"
              f"{row['stalls']:>7}{row['timeouts']:>9}{row['success_rate']:>8.1%}"
              f"{row['mean_path_ratio']:>12.3f}{row['mean_min_clearance']:>11.3f}")
    print(f"wall time {wall:.1f} s (including starting the workers and JIT compilation "
          "on a first run)")
    if args.json:
        write_json(args.json, {"n": args.n, "seed": args.seed, "noise": args.noise,
                               "wall_time_s": wall, "navigators": table})
    if args.plot:
        from subtask_opt.plotting.reactive import save_suite_figure

        with output_file(args.plot) as tmp:
            save_suite_figure(table, tmp, title=f"{args.n} random worlds, seed {args.seed}, "
                                                f"sonar noise {args.noise:g}")
    return EXIT_OK


def _run_fuzzy_table(args: argparse.Namespace) -> int:
    from subtask_opt.planners.reactive.fuzzy import reciprocal_matrix, saaty_weights, table1

    weights = args.weights
    if args.pairwise is not None:
        weights, ci = saaty_weights(reciprocal_matrix(args.pairwise))
        print(f"Saaty weights {', '.join(f'{w:.4f}' for w in weights)} "
              f"(consistency index {ci:.4f})")
    report = table1(weights)
    print("seed paper 001, Table 1: fuzzy decision muD = min_j muGj^wj (eq. 1, 7)")
    for line in report.lines():
        print(line)
    if args.json:
        write_json(args.json, report.to_dict())
    if args.plot:
        from subtask_opt.plotting.reactive import save_table1_figure

        with output_file(args.plot) as tmp:
            save_table1_figure(report, tmp)
    return EXIT_OK if report.matches or report.weighted else EXIT_FAILED
