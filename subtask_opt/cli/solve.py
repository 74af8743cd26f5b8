"""``subtask-opt solve``: order the subtasks of an arm for minimum time."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.stop import TargetCost
from subtask_opt.cli._common import (
    EXIT_FAILED,
    EXIT_OK,
    MAX_INDEX,
    MAX_RUNTIME_S,
    add_no_progress,
    add_outputs,
    add_stop_options,
    animation_output,
    ascii_number,
    failed,
    float_in,
    floats,
    html_output,
    int_in,
    json_output,
    output_file,
    refuse_overwriting_inputs,
    seed,
    stop_criteria,
    write_json,
)


def register(root: argparse._SubParsersAction) -> None:
    """Add the ``solve`` command."""
    from subtask_opt.arm.planar_problem import CONFIGURATION_MODES, DEFAULT_TIME_MODEL
    from subtask_opt.arm.timing import TIME_MODELS
    from subtask_opt.ga.loop import MAX_RUNS
    from subtask_opt.tour.permutation import KICKS_FROM
    from subtask_opt.tour.solve import CONFIGURED_RUNS, PRESETS

    p = root.add_parser(
        "solve",
        help="order subtasks for minimum total travel time",
        description="Find the order of subtasks (and the elbow configuration at each) that "
                    "minimises the arm's total travel time (closed tour); print it with a "
                    "per-leg table, optionally write JSON, figures and the executed trajectory.",
    )
    p.add_argument("--case", required=True, metavar="square20|random30|PATH",
                   help="built-in case or a CSV (header x,y[,theta]) / JSON file of subtasks")
    p.add_argument("--case-seed", type=seed, default=None, metavar="N",
                   help="seed of the random30 generator (default 0)")
    p.add_argument("--robot", default="planar_2r",
                   metavar="planar_2r|asr_twodof|ur3|ur5|ur10|panda|vs060_drill|PATH.urdf",
                   help="robot model (default planar_2r); a 2-joint URDF is a planar arm")
    p.add_argument("--time-model", default=DEFAULT_TIME_MODEL, choices=TIME_MODELS,
                   help=f"time model (default {DEFAULT_TIME_MODEL}: times the arm can execute; "
                        "paper and trapezoid are Cartesian models that may promise legs the "
                        "arm cannot drive)")
    p.add_argument("--k", type=float_in(0.0, 0.5), default=None,
                   help="via-point fraction of the paper time model, in [0, 0.5] (default 0.1)")
    p.add_argument("--elbow", type=int_in(0, 1), default=None, choices=(0, 1),
                   help="IK branch used at every subtask with --configurations fixed "
                        "(0 elbow-down, 1 elbow-up; default 0)")
    p.add_argument("--configurations", choices=CONFIGURATION_MODES, default=None,
                   help="choose the elbow configuration of each subtask with the order "
                        "(default for joint and line) or keep --elbow (default otherwise)")
    p.add_argument("--line-fallback", choices=("joint", "exclude"), default=None,
                   help="line model: drive an infeasible straight line as a joint move "
                        "(default) or forbid it")
    p.add_argument("--check-all-legs", action="store_true",
                   help="paper and trapezoid models: check every straight line for the "
                        "arm's joint limits, not only the tour's legs (JSON diagnostics; "
                        "N(N-1)/2 lines, seconds at N = 1000)")
    p.add_argument("--first", type=int_in(0, MAX_INDEX), default=None, metavar="I",
                   help=f"index of the subtask the tour (or open path) starts at, in [0, "
                        f"{MAX_INDEX}]; with a serial arm's home, the first target after it")
    shape = p.add_argument_group("tour shape and constraints")
    shape.add_argument("--tour", choices=("closed", "open"), default="closed",
                       help="closed: return to the start (default); open: a path that does "
                            "not come back")
    shape.add_argument("--end", type=int_in(0, MAX_INDEX), default=None, metavar="I",
                       help=f"(--tour open) the subtask the path ends at, in [0, {MAX_INDEX}] "
                            "(default: free); a "
                            "serial arm's closed tour: the last target before home")
    shape.add_argument("--home", type=signed_numbers, default=None, metavar="X,Y|Q1,...,QN",
                       help="visited first and last, not a subtask: a point X,Y (m) the planar "
                            "arm must reach, or for a serial arm its home configuration in "
                            "degrees (default there: the robot file's home, if any)")
    shape.add_argument("--home-joints", type=signed_numbers, default=None,
                       metavar="Q1,...,QN",
                       help="the home as a configuration of any arm, in degrees (a planar "
                            "arm starts there in that elbow; for a serial arm the same as "
                            "--home)")
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
    limits.add_argument("--speed-scale", type=float_in(0.0, 1.0, open_low=True), default=None,
                        metavar="F", help="joint speed limits times F, in (0, 1] (after --vmax)")
    limits.add_argument("--accel-scale", type=float_in(0.0, 1.0, open_low=True), default=None,
                        metavar="F", help="joint acceleration (and jerk) limits times F, in "
                                          "(0, 1] (after --amax/--jmax)")
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


PLANAR = "planar"
SERIAL = "serial"
ONLY: dict[str, str] = {
    "case_seed": PLANAR, "k": PLANAR, "elbow": PLANAR, "configurations": PLANAR,
    "line_fallback": PLANAR, "check_all_legs": PLANAR, "animate": PLANAR,
    "scene": SERIAL, "standoff": SERIAL, "axis_step": SERIAL, "tool_frame": SERIAL,
    "limits": SERIAL, "view": SERIAL, "no_detours": SERIAL,
}
"""The options that apply to one kind of robot only; any other option applies to every
robot (``tests/cli/test_solve_options.py`` walks them all). Given for the other kind,
an option is refused (exit 2), never ignored."""


def _given(args: argparse.Namespace, dest: str) -> bool:
    value = getattr(args, dest)
    return value is not None and value is not False


def _option(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def run(args: argparse.Namespace) -> int:
    import time

    from subtask_opt.arm.problem import ArmProblem, load_robot, solve
    from subtask_opt.base.errors import ParameterError
    from subtask_opt.tour.solve import SolverParams

    started = time.monotonic()
    refuse_overwriting_inputs([args.case, args.robot, args.precedence, args.scene, args.limits],
                              [args.json, args.plot, args.trajectory, args.animate, args.view])
    robot = load_robot(args.robot)
    kind = PLANAR if robot.planar else SERIAL
    for dest, only in ONLY.items():
        if only != kind and _given(args, dest):
            raise ParameterError(f"{_option(dest)} applies to {only} arms only; {robot.name} "
                                 f"is {'a planar' if robot.planar else 'a serial'} arm")
    if args.tool_frame is not None or args.limits is not None:
        robot = load_robot(args.robot, tool_frame=args.tool_frame, limits=_limits(args.limits))
    if not robot.planar and args.time_model != "joint":
        raise ParameterError(f"--time-model {args.time_model}: serial arms use the joint model "
                             f"only (the Cartesian models are for planar arms; {robot.name} "
                             "is a serial arm)")
    if _given(args, "case_seed") and args.case != "random30":
        raise ParameterError(f"--case-seed applies to --case random30 only, not {args.case}")
    if any(_given(args, d) for d in ("vmax", "amax", "jmax", "speed_scale", "accel_scale")):
        robot = robot.with_limits(velocity=args.vmax, acceleration=args.amax, jerk=args.jmax,
                                  speed_scale=args.speed_scale or 1.0,
                                  accel_scale=args.accel_scale or 1.0)
    constraints = _constraints(args, robot.planar)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        from subtask_opt.arm.serial_problem import build_progress
        from subtask_opt.base.stop import time_limit

        # --time-limit bounds the build too (checked between its steps), then the search
        with build_progress(not args.no_progress), time_limit(args.max_runtime,
                                                              started=started):
            problem = ArmProblem(_targets(args, robot), robot, home=_home(args, robot),
                                 **_problem_options(args, robot.planar))
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    if args.precedence:  # its indices against the subtasks, the file's line named
        from subtask_opt.tour.constraints import read_precedence

        read_precedence(args.precedence, size=problem.size)
    stop = _stop(args, started)
    if stop == "spent":
        return failed(f"the time limit of {args.max_runtime:g} s was spent building the "
                      "problem (IK, collision checks, leg times) before any search")
    params = SolverParams(preset=args.preset, runs=args.runs)
    if stop is not None and all(isinstance(c, TargetCost) for c in stop):
        configured = not robot.planar or problem.compiled.optimizes_configurations
        stop = stop + params.default_stop(problem.size, configured=configured)
    result = solve(problem, seed=args.seed, stop=stop, params=params,
                   progress=not args.no_progress, certify=args.certify,
                   certify_time_limit=args.certify_time_limit, constraints=constraints)
    report = result.report
    print(result.summary())
    if not args.quiet:
        print(report.leg_table())
    warning = report.warning()
    if warning:
        print(f"warning: {warning}", file=sys.stderr)
    executed = None
    if args.trajectory or args.animate or args.view or not robot.planar:
        executed = _executed(args, result)
        if executed is None and robot.planar:
            return EXIT_FAILED
    if args.json:
        payload = result.to_dict()
        payload["robot"] = robot.name
        payload["time_model"] = report.time_model
        payload["case"] = str(args.case)
        payload["points"] = np.asarray(problem.targets.points).tolist()
        # the same keys for every robot: null when the trajectory was not built
        payload["trajectory"] = None if executed is None else _trajectory_json(*executed)
        write_json(args.json, payload)
        print(f"wrote {args.json}")
    if not robot.planar and executed is None:
        return EXIT_FAILED
    if args.plot:
        _plot(args, problem, result, executed)
    if executed is not None:
        _write_trajectory(args, problem, result, executed[0])
    return EXIT_OK


def _limits(value: str | None) -> Any:
    """``--limits``: a limit-set name, or the per-joint arrays of a JSON file."""
    from subtask_opt.base.files import parse_json, read_text

    if value is None or not value.lower().endswith(".json"):
        return value
    return parse_json(read_text(value, "limits file", max_bytes=1 << 20),
                      f"limits file {value}")


def _targets(args: argparse.Namespace, robot: Any) -> Any:
    from subtask_opt.arm.problem import load_targets
    from subtask_opt.arm.tasks import CASE_NAMES, builtin_case

    if robot.planar and args.case in CASE_NAMES:
        return builtin_case(args.case, robot.model, seed=args.case_seed or 0)
    if robot.planar:
        return load_targets(Path(args.case))
    return load_targets(args.case, standoff=0.0 if args.standoff is None else args.standoff,
                        axis_step=45.0 if args.axis_step is None else args.axis_step)


def _home(args: argparse.Namespace, robot: Any) -> Any:
    """``--home``: a planar arm's point X,Y (m), a serial arm's configuration (degrees);
    ``--home-joints``: any arm's configuration (degrees)."""
    from subtask_opt.base.errors import ParameterError

    if args.home_joints is not None:
        if args.home is not None:
            raise ParameterError("give the home once: --home or --home-joints, not both")
        if len(args.home_joints) != robot.nq:
            raise ParameterError(f"--home-joints takes {robot.nq} joint values (degrees) for "
                                 f"{robot.name}, got {len(args.home_joints)}")
        from subtask_opt.arm.problem import Joints

        return Joints(np.radians(args.home_joints))
    if args.home is None:
        return None
    if robot.planar:
        if len(args.home) != 2:
            raise ParameterError(f"--home takes a point X,Y for a planar arm, got "
                                 f"{len(args.home)} numbers")
        return tuple(args.home)
    if len(args.home) != robot.nq:
        raise ParameterError(f"--home takes {robot.nq} joint values (degrees) for "
                             f"{robot.name}, got {len(args.home)}")
    return np.radians(np.asarray(args.home, dtype=float))


def _problem_options(args: argparse.Namespace, planar: bool) -> dict[str, Any]:
    if not planar:
        return {"scene": args.scene, "detours": not args.no_detours}
    return {"time_model": args.time_model, "first": args.first,
            "k": 0.1 if args.k is None else args.k,
            "elbow": 0 if args.elbow is None else args.elbow,
            "configurations": args.configurations,
            "line_fallback": args.line_fallback or "joint",
            "check_all_legs": args.check_all_legs}


def _stop(args: argparse.Namespace, started: float) -> Any:
    """The stopping options; ``--time-limit`` bounds the whole run, so the search gets
    what building the problem (IK, collision checks, leg times) left of it ("spent": none)."""
    import time

    from subtask_opt.base.stop import MaxRuntime

    stop = stop_criteria(args)
    if args.max_runtime is None or stop is None:
        return stop
    left = args.max_runtime - (time.monotonic() - started)
    if left <= 0:
        return "spent"
    return [MaxRuntime(left) if isinstance(c, MaxRuntime) else c for c in stop]


def _trajectory_json(trajectory: Any, check: Any) -> dict[str, Any]:
    """The ``trajectory`` entry of ``--json``: its check and the kind of every leg."""
    return {**check.to_dict(), "duration": trajectory.duration,
            "legs": [leg.kind for leg in trajectory.legs]}


def _constraints(args: argparse.Namespace, planar: bool) -> Any:
    """The ``TourConstraints`` of the shape options."""
    from subtask_opt.tour.constraints import TourConstraints, read_precedence

    pairs = read_precedence(args.precedence) if args.precedence else ()
    # a planar arm's --first is its problem's first subtask (ArmProblem.first)
    start = None if planar else args.first
    return TourConstraints(tour=args.tour, start=start, end=args.end, precedence=pairs)


def _executed(args: argparse.Namespace, result: Any) -> Any:
    """The tour's trajectory and its check; None (after one line) when it is invalid."""
    from subtask_opt.arm.problem import trajectory, validate

    executed = trajectory(result)
    check = validate(executed, dt=min(args.dt, 1e-3 if executed.planar else 0.005))
    print(check.summary())
    if not check.ok:
        print("subtask-opt: failed: the executed trajectory is invalid: "
              + "; ".join(check.violations), file=sys.stderr)
        return None
    model = executed.time_model
    if model in ("paper", "trapezoid"):
        print(f"note: the {model} model promised {result.total_time:.4f} s; driving its "
              f"straight lines within the joint limits takes {executed.duration:.4f} s")
    return executed, check


def _plot(args: argparse.Namespace, problem: Any, result: Any, executed: Any) -> None:
    """``--plot``: the planar tour and its convergence, or a serial arm's tool path."""
    if problem.robot.planar:
        from subtask_opt.plotting.sequencing import save_solution_figure

        with output_file(args.plot) as tmp:
            save_solution_figure(result, problem.compiled, tmp)
    else:
        from subtask_opt.plotting.cell_geometry import detour_legs
        from subtask_opt.plotting.serial import plot_serial_tour

        trajectory = executed[0]
        q = trajectory.states(trajectory.sample_times(0.01))[0]
        serial = problem.compiled
        with output_file(args.plot) as tmp:
            plot_serial_tour(serial.arm, serial.targets.points, trajectory.tool_positions(q),
                             result.leg_times, result.order, tmp,
                             title=_title(args, problem, result), q_home=serial.home,
                             scene=serial.scene, detours=detour_legs(trajectory))
    print(f"wrote {args.plot}")


def _title(args: argparse.Namespace, problem: Any, result: Any) -> str:
    return (f"{problem.robot.name}: {problem.size} targets from {args.case}, "
            f"{result.total_time:.2f} s executed")


def _write_trajectory(args: argparse.Namespace, problem: Any, result: Any,
                      trajectory: Any) -> None:
    """``--trajectory`` (CSV), ``--animate`` (planar GIF) and ``--view`` (3-D HTML)."""
    if args.trajectory:
        with output_file(args.trajectory) as tmp:
            trajectory.to_csv(tmp, args.dt)
        print(f"wrote {args.trajectory}")
    if args.animate:
        from subtask_opt.plotting.trajectory import animate_tour

        with output_file(args.animate) as tmp:
            animate_tour(problem.compiled, trajectory, tmp,
                         progress=not args.no_progress and sys.stderr.isatty())
        print(f"wrote {args.animate}")
    if args.view:
        from subtask_opt.plotting.arm3d import write_tour_html
        from subtask_opt.plotting.cell_geometry import detour_legs

        serial = problem.compiled
        times = trajectory.sample_times(0.01)
        q = trajectory.states(times)[0]
        with output_file(args.view) as tmp:
            write_tour_html(tmp, serial.arm, times, q, targets=serial.targets.points,
                            axes=serial.targets.axes, scene=serial.scene, order=result.order,
                            title=_title(args, problem, result),
                            detours=detour_legs(trajectory))
        print(f"wrote {args.view}")


# ---------------------------------------------------------------- serial arms (6-/7-DOF)

_SERIAL_FLAGS = ("view", "scene", "standoff", "axis_step", "tool_frame", "limits",
                 "no_detours")


def _add_serial_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group(
        "serial arms only (--robot ur3|ur5|ur10|panda|vs060_drill|PATH.urdf; --case is a CSV "
        "of x,y,z,dx,dy,dz or x,y,z,qx,qy,qz,qw rows)")
    add_cell_options(g)
    g.add_argument("--limits", metavar="NAME|FILE.json",
                   help="a named limit set of the robot or a JSON file of per-joint limits")
    g.add_argument("--view", metavar="OUT.html", type=html_output,
                   help="write the executed tour as an offline 3-D HTML animation")
    g.add_argument("--no-detours", action="store_true",
                   help="forbid legs whose straight joint motion collides instead of "
                        "planning them around the obstacles (OMPL RRTConnect)")


def add_cell_options(g: Any) -> None:
    """A serial arm's cell: ``--scene``, ``--standoff``, ``--axis-step``, ``--tool-frame``
    (``solve`` and ``batch``)."""
    g.add_argument("--scene", metavar="SCENE.json|MESH.stl", default=None,
                   help='the cell: {"boxes": [...], "meshes": [{"name", "file", "scale", '
                        '"position", "rotation"}], "tool": {"frame", "tcp", "boxes", '
                        '"meshes"}} (subtask_opt.cell.scene), or one mesh file at the origin')
    g.add_argument("--standoff", type=float_in(-1.0, 1.0), default=None, metavar="M",
                   help="tool standoff along its axis in metres (default 0)")
    g.add_argument("--axis-step", type=float_in(5.0, 360.0), default=None,
                   metavar="DEG", help="sampling step of the free rotation about a tool axis, "
                                       "in [5, 360] (default 45); targets x 360 / DEG may be "
                                       "at most 2500 poses")
    g.add_argument("--tool-frame", metavar="FRAME", help="tool frame (default: the robot's)")


def signed_numbers(text: str) -> tuple[float, ...]:
    """Comma-separated finite numbers in [-1e4, 1e4] (a point in m, or joint values in degrees)."""
    import math

    try:
        values = tuple(float(ascii_number(v)) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, got {text!r}") from None
    if not values or not all(math.isfinite(v) and abs(v) <= 1e4 for v in values):
        raise argparse.ArgumentTypeError(f"expected finite numbers in [-1e4, 1e4], got {text!r}")
    return values


