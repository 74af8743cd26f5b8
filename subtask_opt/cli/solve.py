"""``subtask-opt solve``: order the subtasks of a planar arm for minimum time."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from subtask_opt.cli._common import non_negative_int, positive_float, positive_int, write_json


def register(root: argparse._SubParsersAction) -> None:
    """Add the ``solve`` command."""
    p = root.add_parser(
        "solve",
        help="order subtasks for minimum total travel time",
        description="Find the order of subtasks that minimises the arm's total travel time "
                    "(closed tour), print it with a per-leg table, optionally write JSON "
                    "and figures.",
    )
    p.add_argument("--case", required=True, metavar="square20|random30|PATH",
                   help="built-in case or a CSV (header x,y[,theta]) / JSON file of subtasks")
    p.add_argument("--case-seed", type=non_negative_int, default=0, metavar="N",
                   help="seed of the random30 generator (default 0)")
    p.add_argument("--robot", default="planar_2r", metavar="planar_2r|asr_twodof|PATH.urdf",
                   help="robot model (default planar_2r)")
    p.add_argument("--time-model", default="trapezoid", metavar="MODEL",
                   help="paper | trapezoid | joint | line (default trapezoid)")
    p.add_argument("--k", type=float, default=0.1,
                   help="via-point fraction of the paper time model (default 0.1)")
    p.add_argument("--elbow", type=int, default=0, choices=(0, 1),
                   help="IK branch used at every subtask with --configurations fixed "
                        "(0 elbow-down, 1 elbow-up; default 0)")
    p.add_argument("--configurations", choices=("optimize", "fixed"), default=None,
                   help="choose the elbow configuration of each subtask with the order "
                        "(default for joint and line) or keep --elbow (default otherwise)")
    p.add_argument("--line-fallback", choices=("joint", "exclude"), default="joint",
                   help="line model: drive an infeasible straight line as a joint move "
                        "(default) or forbid it")
    p.add_argument("--first", type=non_negative_int, default=None, metavar="I",
                   help="index of the subtask the tour starts and ends at")
    p.add_argument("--preset", default="default", choices=("default", "paper"),
                   help="solver preset (default: micro-GA with local search)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="solver seed (default 0)")
    stop = p.add_argument_group("stopping (any criterion given stops the run)")
    stop.add_argument("--max-generations", type=positive_int, metavar="N")
    stop.add_argument("--max-runtime", type=positive_float, metavar="SECONDS")
    stop.add_argument("--no-improvement", type=positive_int, metavar="N",
                      help="stop after N generations without a better tour")
    stop.add_argument("--target", type=float, metavar="SECONDS",
                      help="stop once the total time is at most this")
    out = p.add_argument_group("output")
    out.add_argument("--json", metavar="OUT.json", help="write the result as JSON")
    out.add_argument("--plot", metavar="OUT.png",
                     help="write the tour over the workspace and the convergence plot")
    out.add_argument("--trajectory", metavar="OUT.csv",
                     help="write the executed joint trajectory (t,q1,q2,dq1,dq2,x,y), "
                          "checked against the joint limits")
    out.add_argument("--dt", type=float, default=0.01, metavar="SECONDS",
                     help="sampling step of --trajectory (default 0.01)")
    out.add_argument("--animate", metavar="OUT.gif",
                     help="write a GIF of the arm executing the tour")
    out.add_argument("--quiet", action="store_true", help="print only the summary")
    p.set_defaults(handler=run)


def _stop_criteria(args: argparse.Namespace) -> list | None:
    from subtask_opt.base.stop import MaxGenerations, MaxRuntime, NoImprovement, TargetCost

    criteria: list = []
    if args.max_generations is not None:
        criteria.append(MaxGenerations(args.max_generations))
    if args.max_runtime is not None:
        criteria.append(MaxRuntime(args.max_runtime))
    if args.no_improvement is not None:
        criteria.append(NoImprovement(args.no_improvement))
    if args.target is not None:
        criteria.append(TargetCost(args.target))
    return criteria or None


def run(args: argparse.Namespace) -> int:
    from subtask_opt.arm.model import load_arm
    from subtask_opt.arm.sequencing import SequencingProblem, SolverParams, solve
    from subtask_opt.arm.tasks import CASE_NAMES, builtin_case, load_subtasks
    from subtask_opt.base.errors import InputDataError, require_positive

    # fail before the search, not after
    if args.trajectory or args.animate:
        require_positive("solve", "dt", args.dt)
    if args.animate and not args.animate.lower().endswith(".gif"):
        raise InputDataError(f"animation file must end in .gif, got {args.animate!r}")
    arm = load_arm(args.robot)
    if args.case in CASE_NAMES:
        subtasks = builtin_case(args.case, arm, seed=args.case_seed)
    else:
        subtasks = load_subtasks(Path(args.case))
    configurations = args.configurations or (
        "optimize" if args.time_model in ("joint", "line") else "fixed")
    problem = SequencingProblem(subtasks, arm, time_model=args.time_model, first=args.first,
                                k=args.k, elbow=args.elbow, configurations=configurations,
                                line_fallback=args.line_fallback)
    stop = _stop_criteria(args)
    if stop is not None and all(type(c).__name__ == "TargetCost" for c in stop):
        stop = stop + SolverParams(preset=args.preset).default_stop()
    result = solve(problem, seed=args.seed, stop=stop, params=SolverParams(preset=args.preset),
                   progress=sys.stderr.isatty())
    print(result.summary())
    if not args.quiet:
        print(format_leg_table(result, problem))
    _warn_infeasible(result, problem)
    trajectory, report = (_executed(args, problem, result) if args.trajectory or args.animate
                          else (None, None))
    if args.json:
        payload = result.to_dict()
        payload["case"] = args.case
        payload["points"] = problem.subtasks.points.tolist()
        if trajectory is not None:
            payload["trajectory"] = {
                "duration": trajectory.duration, "valid": report.ok,
                "max_velocity_ratio": max(report.max_velocity_ratio),
                "max_acceleration_ratio": max(report.max_acceleration_ratio),
                "legs": [leg.kind for leg in trajectory.legs]}
        write_json(args.json, payload)
        print(f"wrote {args.json}")
    if args.plot:
        from subtask_opt.plotting.sequencing import save_solution_figure

        save_solution_figure(result, problem, args.plot)
        print(f"wrote {args.plot}")
    if trajectory is not None:
        _write_trajectory(args, problem, trajectory)
    return 0


def _executed(args: argparse.Namespace, problem, result):
    """The tour's trajectory, validated (an invalid one is an error, never written)."""
    from subtask_opt.arm.trajectory import tour_trajectory, validate_trajectory
    from subtask_opt.base.errors import SubtaskOptError

    trajectory = tour_trajectory(problem, result)
    report = validate_trajectory(trajectory, dt=min(args.dt, 1e-3))
    print(report.summary())
    if not report.ok:
        raise SubtaskOptError("executed trajectory breaks a joint limit: "
                              + "; ".join(report.violations))
    if problem.time_model in ("paper", "trapezoid"):
        print(f"note: the {problem.time_model} model promised {result.total_time:.4f} s; "
              f"driving its straight lines within the joint limits takes "
              f"{trajectory.duration:.4f} s")
    return trajectory, report


def _write_trajectory(args: argparse.Namespace, problem, trajectory) -> None:
    if args.trajectory:
        trajectory.to_csv(args.trajectory, args.dt)
        print(f"wrote {args.trajectory}")
    if args.animate:
        from subtask_opt.plotting.trajectory import animate_tour

        animate_tour(problem, trajectory, args.animate, progress=sys.stderr.isatty())
        print(f"wrote {args.animate}")


def format_leg_table(result, problem) -> str:
    """One row per leg: from, to, elbow branches, distance, time, move, and notes.

    The notes give the joint-limit check of the Cartesian models' straight
    lines, and for the line model why a leg is not a straight line.
    """
    pts = problem.subtasks.points
    timing = problem.timing
    check = timing.leg_check
    configs = result.configurations
    rows = [f"{'leg':>4} {'from':>5} {'to':>5} {'elbow':>6} {'dist [m]':>9} {'time [s]':>9} "
            f"{'move':>5}  notes"]
    n = len(result.order)
    for i in range(n):
        a, b = int(result.order[i]), int(result.order[(i + 1) % n])
        ca, cb = int(configs[a]), int(configs[b])
        dist = float(((pts[a] - pts[b]) ** 2).sum() ** 0.5)
        elbow = "du"[ca] + ("->" + "du"[cb] if ca != cb else "")
        move = result.leg_moves[i] if result.leg_moves is not None else "line"
        notes = []
        if ca != cb:
            notes.append("elbow change")
        if check is not None:
            if check.outside_annulus[a, b]:
                notes.append("straight line impossible (inner disc, joint limit or elbow change)")
            elif check.speed_ratio[a, b] > 1.0:
                notes.append(f"joint speed x{check.speed_ratio[a, b]:.2f} over limit")
        why = timing.line_failure(a, b, ca, cb) if problem.time_model == "line" else None
        if why is not None and ca == cb:
            notes.append(f"line infeasible ({why})")
        rows.append(f"{i:>4} {a:>5} {b:>5} {elbow:>6} {dist:>9.4f} {result.leg_times[i]:>9.4f} "
                    f"{move:>5}  {', '.join(notes)}")
    return "\n".join(rows)


def _warn_infeasible(result, problem) -> None:
    """Warn when the tour's straight lines would break the arm's joint limits."""
    check = problem.timing.leg_check
    if check is None:
        return
    order = result.order
    nxt = np.roll(order, -1)
    impossible = int(np.count_nonzero(check.outside_annulus[order, nxt]))
    over = check.speed_ratio[order, nxt]
    fast = int(np.count_nonzero((over > 1.0) & ~check.outside_annulus[order, nxt]))
    if impossible or fast:
        worst = float(np.max(np.where(np.isfinite(over), over, 0.0)))
        print(f"warning: {impossible + fast} of the tour's {len(order)} straight-line legs break "
              f"a joint limit ({impossible} impossible as a straight line, {fast} over a joint "
              f"speed limit, worst x{worst:.2f}); use --time-model joint or line for times the "
              "arm can achieve", file=sys.stderr)
