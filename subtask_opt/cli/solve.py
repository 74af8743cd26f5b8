"""``subtask-opt solve``: order the subtasks of an arm for minimum time."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

from subtask_opt.base.stop import TargetCost
from subtask_opt.cli._common import (
    EXIT_FAILED,
    EXIT_OK,
    MAX_RUNTIME_S,
    add_no_progress,
    add_outputs,
    add_stop_options,
    animation_output,
    float_in,
    floats,
    html_output,
    int_in,
    json_output,
    non_negative_int,
    refuse_overwriting_inputs,
    seed,
    stop_criteria,
    write_json,
)


def register(root: argparse._SubParsersAction) -> None:
    """Add the ``solve`` command."""
    from subtask_opt.arm.sequencing import (
        CONFIGURATION_MODES,
        CONFIGURED_RUNS,
        DEFAULT_TIME_MODEL,
        PRESETS,
    )
    from subtask_opt.arm.timing import TIME_MODELS
    from subtask_opt.ga.loop import MAX_RUNS
    from subtask_opt.ga.permutation import KICKS_FROM

    p = root.add_parser(
        "solve",
        help="order subtasks for minimum total travel time",
        description="Find the order of subtasks (and the elbow configuration at each) that "
                    "minimises the arm's total travel time (closed tour); print it with a "
                    "per-leg table, optionally write JSON, figures and the executed trajectory.",
    )
    p.add_argument("--case", required=True, metavar="square20|random30|PATH",
                   help="built-in case or a CSV (header x,y[,theta]) / JSON file of subtasks")
    p.add_argument("--case-seed", type=seed, default=0, metavar="N",
                   help="seed of the random30 generator (default 0)")
    p.add_argument("--robot", default="planar_2r", metavar="planar_2r|asr_twodof|PATH.urdf",
                   help="robot model (default planar_2r)")
    p.add_argument("--time-model", default=DEFAULT_TIME_MODEL, choices=TIME_MODELS,
                   help=f"time model (default {DEFAULT_TIME_MODEL}: times the arm can execute; "
                        "paper and trapezoid are Cartesian models that may promise legs the "
                        "arm cannot drive)")
    p.add_argument("--k", type=float_in(0.0, 0.5), default=0.1,
                   help="via-point fraction of the paper time model, in [0, 0.5] (default 0.1)")
    p.add_argument("--elbow", type=int, default=0, choices=(0, 1),
                   help="IK branch used at every subtask with --configurations fixed "
                        "(0 elbow-down, 1 elbow-up; default 0)")
    p.add_argument("--configurations", choices=CONFIGURATION_MODES, default=None,
                   help="choose the elbow configuration of each subtask with the order "
                        "(default for joint and line) or keep --elbow (default otherwise)")
    p.add_argument("--line-fallback", choices=("joint", "exclude"), default="joint",
                   help="line model: drive an infeasible straight line as a joint move "
                        "(default) or forbid it")
    p.add_argument("--check-all-legs", action="store_true",
                   help="paper and trapezoid models: check every straight line for the "
                        "arm's joint limits, not only the tour's legs (JSON diagnostics; "
                        "N(N-1)/2 lines, seconds at N = 1000)")
    p.add_argument("--first", type=non_negative_int, default=None, metavar="I",
                   help="index of the subtask the tour (or open path) starts at")
    shape = p.add_argument_group("tour shape and constraints")
    shape.add_argument("--tour", choices=("closed", "open"), default="closed",
                       help="closed: return to the start (default); open: a path that does "
                            "not come back")
    shape.add_argument("--end", type=non_negative_int, default=None, metavar="I",
                       help="(--tour open) the subtask the path ends at (default: free)")
    shape.add_argument("--home", type=_signed_numbers, default=None, metavar="X,Y|Q1,...,QN",
                       help="visited first and last, not a subtask: a point X,Y (m) the planar "
                            "arm must reach, or for a serial arm its home configuration in "
                            "degrees (default there: the robot file's home, if any)")
    shape.add_argument("--precedence", default=None, metavar="FILE",
                       help="text file of lines 'a,b': subtask a before subtask b (0-based "
                            "row indices, as in the printed order)")
    p.add_argument("--preset", default="default", choices=PRESETS,
                   help="solver preset (default: micro-GA with local search)")
    p.add_argument("--seed", type=seed, default=0, help="solver seed in [0, 2**63) (default 0)")
    p.add_argument("--runs", type=int_in(1, MAX_RUNS), default=None, metavar="N",
                   help=f"independent GA runs, the best kept, N in [1, {MAX_RUNS}] (default "
                        f"{CONFIGURED_RUNS} when a planar arm's elbows are chosen below "
                        f"{KICKS_FROM} subtasks, else 1)")
    p.add_argument("--certify", action="store_true",
                   help="prove the answer optimal (a MILP for fixed configurations, a branch "
                        "and cut when the elbows are chosen), or report the remaining gap")
    p.add_argument("--certify-time-limit", type=float_in(0.0, MAX_RUNTIME_S, open_low=True),
                   default=60.0, metavar="SECONDS", help="time for --certify (default 60)")
    limits = p.add_argument_group("joint limits (replace the robot's; a scalar or one per joint)")
    limits.add_argument("--vmax", type=floats, metavar="V[,V]", help="joint speed limits, rad/s")
    limits.add_argument("--amax", type=floats, metavar="A[,A]",
                        help="joint acceleration limits, rad/s^2")
    limits.add_argument("--jmax", type=floats, metavar="J[,J]", help="joint jerk limits, rad/s^3")
    add_stop_options(p, title="stopping (any criterion given stops the run)", target=True)
    out = p.add_argument_group("output")
    add_outputs(out, plot="the tour over the workspace and the convergence plot")
    out.add_argument("--trajectory", metavar="OUT.csv", type=json_output,
                     help="write the executed joint trajectory (t,q1,q2,dq1,dq2,x,y), "
                          "checked against the joint limits")
    out.add_argument("--dt", type=float_in(1e-4, 1.0), default=0.01, metavar="SECONDS",
                     help="sampling step of --trajectory, in [1e-4, 1] (default 0.01)")
    out.add_argument("--animate", metavar="OUT.gif", type=animation_output,
                     help="write a GIF of the arm executing the tour")
    out.add_argument("--quiet", action="store_true", help="print only the summary (no leg table)")
    add_no_progress(out)
    _add_serial_options(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    if _is_serial(args):
        return _run_serial(args)
    from subtask_opt.arm.model import load_arm
    from subtask_opt.arm.sequencing import SequencingProblem, SolverParams, solve
    from subtask_opt.arm.tasks import CASE_NAMES, builtin_case, load_subtasks

    refuse_overwriting_inputs([args.case, args.robot, args.precedence],
                              [args.json, args.plot, args.trajectory, args.animate])
    constraints = _constraints(args)
    arm = load_arm(args.robot)
    if args.vmax or args.amax or args.jmax:
        arm = arm.with_joint_limits(velocity=args.vmax, acceleration=args.amax, jerk=args.jmax)
    if args.case in CASE_NAMES:
        subtasks = builtin_case(args.case, arm, seed=args.case_seed)
    else:
        subtasks = load_subtasks(Path(args.case))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        problem = SequencingProblem(subtasks, arm, time_model=args.time_model, first=args.first,
                                    k=args.k, elbow=args.elbow,
                                    configurations=args.configurations,
                                    line_fallback=args.line_fallback,
                                    check_all_legs=args.check_all_legs)
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    stop = stop_criteria(args)
    params = SolverParams(preset=args.preset, runs=args.runs)
    if stop is not None and all(isinstance(c, TargetCost) for c in stop):
        stop = stop + params.default_stop(len(subtasks),
                                          configured=problem.optimizes_configurations)
    result = solve(problem, seed=args.seed, stop=stop, params=params,
                   progress=not args.no_progress, certify=args.certify,
                   certify_time_limit=args.certify_time_limit, constraints=constraints)
    report = result.report
    assert report is not None
    print(result.summary())
    if not args.quiet:
        print(report.leg_table())
    warning = report.warning()
    if warning:
        print(f"warning: {warning}", file=sys.stderr)
    executed = None
    if args.trajectory or args.animate:
        executed = _executed(args, problem, result)
        if executed is None:
            return EXIT_FAILED
    if args.json:
        payload = result.to_dict()
        payload["case"] = args.case
        payload["points"] = problem.subtasks.points.tolist()
        if executed is not None:
            trajectory, check = executed
            payload["trajectory"] = {
                "duration": trajectory.duration, "valid": check.ok,
                "max_velocity_ratio": max(check.max_velocity_ratio),
                "max_acceleration_ratio": max(check.max_acceleration_ratio),
                "max_jerk_ratio": (None if check.max_jerk_ratio is None
                                   else max(check.max_jerk_ratio)),
                "valid_tolerances": {"rtol": check.rtol, "jtol": check.jtol},
                "legs": [leg.kind for leg in trajectory.legs]}
        write_json(args.json, payload)
        print(f"wrote {args.json}")
    if args.plot:
        from subtask_opt.plotting.sequencing import save_solution_figure

        save_solution_figure(result, problem, args.plot)
        print(f"wrote {args.plot}")
    if executed is not None:
        _write_trajectory(args, problem, executed[0])
    return EXIT_OK


def _constraints(args: argparse.Namespace) -> Any:
    """The ``TourConstraints`` of the shape options (an unsupported output: one error line)."""
    from subtask_opt.arm.constraints import TourConstraints, read_precedence
    from subtask_opt.base.errors import ParameterError

    if args.home is not None and len(args.home) != 2:
        raise ParameterError(f"--home takes a point X,Y, got {len(args.home)} numbers")
    pairs = read_precedence(args.precedence) if args.precedence else ()
    constraints = TourConstraints(tour=args.tour, end=args.end,
                                  home=None if args.home is None else tuple(args.home),
                                  precedence=pairs)
    if args.tour == "open" or args.home is not None:
        wanted = [flag for flag, value in (("--plot", args.plot), ("--trajectory",
                  args.trajectory), ("--animate", args.animate)) if value]
        if wanted:
            raise ParameterError(f"{', '.join(wanted)} draw closed tours over the subtasks; "
                                 "not available with --tour open or --home yet")
    return constraints


def _executed(args: argparse.Namespace, problem: Any, result: Any) -> Any:
    """The tour's trajectory and its check; None (after one line) when it is invalid."""
    from subtask_opt.arm.trajectory import tour_trajectory, validate_trajectory

    trajectory = tour_trajectory(problem, result)
    check = validate_trajectory(trajectory, dt=min(args.dt, 1e-3))
    print(check.summary())
    if not check.ok:
        print("subtask-opt: failed: the executed trajectory breaks a limit: "
              + "; ".join(check.violations), file=sys.stderr)
        return None
    if problem.time_model in ("paper", "trapezoid"):
        print(f"note: the {problem.time_model} model promised {result.total_time:.4f} s; "
              f"driving its straight lines within the joint limits takes "
              f"{trajectory.duration:.4f} s")
    return trajectory, check


def _write_trajectory(args: argparse.Namespace, problem: Any, trajectory: Any) -> None:
    if args.trajectory:
        trajectory.to_csv(args.trajectory, args.dt)
        print(f"wrote {args.trajectory}")
    if args.animate:
        from subtask_opt.plotting.trajectory import animate_tour

        animate_tour(problem, trajectory, args.animate,
                     progress=not args.no_progress and sys.stderr.isatty())
        print(f"wrote {args.animate}")


# ---------------------------------------------------------------- serial arms (6-/7-DOF)

_SERIAL_FLAGS = ("view", "scene", "standoff", "axis_step", "tool_frame", "limits")


def _add_serial_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group(
        "serial arms (--robot ur3|ur5|ur10|panda|vs060_drill|PATH.urdf; --case is a CSV of "
        "x,y,z,dx,dy,dz or x,y,z,qx,qy,qz,qw rows)")
    g.add_argument("--scene", metavar="SCENE.json",
                   help='boxes to avoid: {"boxes": [{"name", "center", "half_extents", '
                        '"rotation"}]}')
    g.add_argument("--standoff", type=float_in(-1.0, 1.0), default=None, metavar="M",
                   help="tool standoff along its axis in metres (default 0)")
    g.add_argument("--axis-step", type=float_in(0.0, 360.0, open_low=True), default=None,
                   metavar="DEG", help="sampling step of the free rotation about a tool axis "
                                       "(default 45)")
    g.add_argument("--tool-frame", metavar="FRAME", help="tool frame (default: the robot's)")
    g.add_argument("--limits", metavar="NAME|FILE.json",
                   help="a named limit set of the robot or a JSON file of per-joint limits")
    g.add_argument("--view", metavar="OUT.html", type=html_output,
                   help="write the executed tour as an offline 3-D HTML animation")


def _signed_numbers(text: str) -> tuple[float, ...]:
    """Comma-separated finite numbers in [-1e4, 1e4] (a point in m, or joint values in degrees)."""
    import math

    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, got {text!r}") from None
    if not values or not all(math.isfinite(v) and abs(v) <= 1e4 for v in values):
        raise argparse.ArgumentTypeError(f"expected finite numbers in [-1e4, 1e4], got {text!r}")
    return values


def _is_serial(args: argparse.Namespace) -> bool:
    from subtask_opt.arm.serial import SERIAL_ROBOT_NAMES

    if args.robot in SERIAL_ROBOT_NAMES or any(
            getattr(args, f) is not None for f in _SERIAL_FLAGS):
        return True
    return str(args.robot).lower().endswith(".urdf") and _movable_joints(args.robot) != 2


def _movable_joints(urdf: str) -> int:
    """Number of revolute/prismatic/continuous joints of a URDF (-1 if unreadable)."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(urdf).getroot()
    except (OSError, ET.ParseError):
        return -1
    return sum(j.get("type") in ("revolute", "prismatic", "continuous")
               for j in root.iter("joint"))


def _run_serial(args: argparse.Namespace) -> int:
    from subtask_opt.arm.sequencing import SolverParams
    from subtask_opt.arm.serial_problem import serial_problem_from_files, solve_serial
    from subtask_opt.arm.serial_trajectory import serial_trajectory, validate_serial_trajectory
    from subtask_opt.base.errors import ParameterError

    if args.time_model != "joint":
        raise ParameterError(f"--time-model {args.time_model}: serial arms use the joint "
                             "model only")
    refuse_overwriting_inputs([args.case, args.robot, args.scene, args.limits],
                              [args.json, args.trajectory, args.plot, args.view])
    if args.animate:
        raise ParameterError("--animate draws the planar arm; use --view OUT.html for a serial arm")
    problem = serial_problem_from_files(
        args.robot, args.case, scene=args.scene, home_deg=args.home,
        standoff=0.0 if args.standoff is None else args.standoff,
        axis_step=45.0 if args.axis_step is None else args.axis_step,
        tool_frame=args.tool_frame, limits=args.limits)
    stop = stop_criteria(args)
    params = SolverParams(preset=args.preset, runs=args.runs)
    if stop is not None and all(isinstance(c, TargetCost) for c in stop):
        stop = stop + params.default_stop(problem.size)
    result = solve_serial(problem, seed=args.seed, stop=stop, params=params)
    print(result.summary())
    trajectory = serial_trajectory(problem, result)
    check = validate_serial_trajectory(trajectory, result, dt=min(args.dt, 0.005))
    print(check.summary())
    if args.json:
        payload = result.to_dict()
        payload["robot"] = problem.arm.name
        payload["case"] = str(args.case)
        payload["trajectory"] = {"duration": trajectory.duration, "valid": check.ok,
                                 "violations": list(check.violations)}
        write_json(args.json, payload)
        print(f"wrote {args.json}")
    if not check.ok:
        print("subtask-opt: failed: the executed trajectory is invalid: "
              + "; ".join(check.violations), file=sys.stderr)
        return EXIT_FAILED
    if args.trajectory:
        trajectory.to_csv(args.trajectory, args.dt)
        print(f"wrote {args.trajectory}")
    if args.plot or args.view:
        _serial_figures(args, problem, result, trajectory)
    return EXIT_OK


def _serial_figures(args: argparse.Namespace, problem: Any, result: Any, trajectory: Any) -> None:
    """``--plot`` (targets, tool path, time per leg) and ``--view`` (3-D HTML animation)."""
    times = trajectory.sample_times(0.01)
    q = trajectory.states(times)[0]
    targets = problem.targets
    title = (f"{problem.arm.name}: {len(targets)} targets from {args.case}, "
             f"{result.total_time:.2f} s executed")
    if args.plot:
        from subtask_opt.plotting.serial import plot_serial_tour

        plot_serial_tour(problem.arm, targets.points, trajectory.tool_positions(q),
                         result.leg_times, result.order, args.plot, title=title,
                         q_home=problem.home, scene=problem.scene)
        print(f"wrote {args.plot}")
    if args.view:
        from subtask_opt.plotting.arm3d import write_tour_html

        write_tour_html(args.view, problem.arm, times, q, targets=targets.points,
                        axes=targets.axes, scene=problem.scene, order=result.order, title=title)
        print(f"wrote {args.view}")
