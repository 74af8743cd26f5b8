"""RoboTSP's drilling benchmark (ICRA 2018) on our pipeline, beside its methods.

The 245 holes of ``../shared/data/robotsp`` and RoboTSP's subsets (25 ... 245
holes) on ``vs060_drill`` with RoboTSP's ``robotsp`` limit set, its home
configuration, a 0.01 m standoff and a 45 degree axis step, the panel and the
pedestal boxes as the scene. One :class:`~subtask_opt.arm.serial_problem.SerialProblem`
per subset (IK, collision filter, leg matrix) is shared by every method:

* ``ours``: :func:`~subtask_opt.arm.serial_problem.solve_serial_problem`;
* ``robotsp``: RoboTSP's method (Euclidean TSP on the hole positions, then
  the best configurations through the layers in that order);
* ``tsp_cspace``: the most manipulable configuration per hole, then a TSP in
  joint space;
* ``elkai_gtsp``: LKH on the GTSP (Noon-Bean), a GLKH stand-in.

* ``robotsp_planned``: RoboTSP's whole pipeline, "plan every leg after sequencing"
  (:func:`plan_after`): RoboTSP's tour, then each of its straight legs that collides
  planned once with the same planner ours uses (OMPL RRTConnect + simplification,
  :func:`~subtask_opt.cell.detour.plan_detour`, for RoboTSP's BiRRT + shortcutting).

The three peers come from :mod:`subtask_opt.tour.peers` (imported lazily; a
missing module or function is reported, not faked). Every answer is executed
with the same ruckig legs and validated
(:func:`~subtask_opt.arm.trajectory.validate`: the samples and every straight joint
segment swept against the panel and the pedestal). Ours checks the legs its best tours
use inside the search and plans those that collide (lazily, their planned times
entering the search); the peers' legs are straight joint moves whose collisions are only
counted, and ``robotsp_planned`` plans them after the search.
RoboTSP's published figures (``published.json``) are printed beside ours as
context: the robot frames were reconstructed, so absolute times compare only
loosely.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt._kernel_cache import compile_seconds
from subtask_opt.base.errors import InputDataError, ParameterError, require_int
from subtask_opt.base.stop import MaxGenerations, NoImprovement, StoppingCriterion

PEERS = ("robotsp", "tsp_cspace", "elkai_gtsp")
HOME_DEG = (0.0, -20.0, 130.0, 0.0, 70.0, 0.0)
ALTERNATIVES_MAX_HOLES = 100
"""Largest subset whose configurations include the +-2 pi alternatives by default."""


def _load(data_dir: Path) -> tuple[np.ndarray, dict[str, list[int]], dict[str, Any]]:
    try:
        rows = np.loadtxt(data_dir / "targets.csv", delimiter=",", skiprows=1)
        subsets = json.loads((data_dir / "subsets.json").read_text())["subsets"]
        published = json.loads((data_dir / "published.json").read_text())
    except (OSError, ValueError, KeyError) as exc:
        raise InputDataError(f"cannot read the RoboTSP data in {data_dir}: {exc}") from None
    return rows, subsets, published


def _peer(name: str) -> Callable[..., Any] | str:
    """The peer function, or why it is unavailable."""
    try:
        from subtask_opt.tour import peers
    except ImportError as exc:
        return f"subtask_opt.tour.peers not available ({exc})"
    fn = getattr(peers, {"robotsp": "robotsp_method"}.get(name, name), None)
    return fn if callable(fn) else f"subtask_opt.tour.peers has no {name}"


def _manipulability(arm: Any, layers: list[np.ndarray]) -> list[np.ndarray]:
    out = []
    for q in layers:
        values = []
        for row in q:
            jac = arm.jacobian(row)
            values.append(float(np.sqrt(max(np.linalg.det(jac @ jac.T), 0.0))))
        out.append(np.array(values))
    return out


def plan_after(problem: Any, report: Any, *, seed: int = 0, params: Any = None,
               cpu: dict[str, float] | None = None) -> Any:
    """RoboTSP's last step on a sequenced tour (``report``, an
    :func:`~subtask_opt.arm.serial_problem.evaluate_tour` answer): every leg whose straight
    joint motion collides is planned once around the obstacles
    (:func:`~subtask_opt.cell.detour.plan_detour`, one attempt, ``params`` its budgets) and
    driven through its waypoints; the order and configurations stay. A leg the planner
    cannot plan stays straight (and in collision: ``counts["legs_unplanned"]``).

    Returns the report with the detours, their times and ``cpu["planner"]`` /
    ``cpu["collision"]`` (the legs' sweeps) added to ``cpu``.
    """
    import dataclasses

    from subtask_opt.cell.detour import plan_detour

    if problem.checker is None:
        raise ParameterError("plan_after: the problem has no collision checker")
    path = [report.home, *report.configurations[report.order], report.home]
    planned = np.array(report.planned_leg_times, dtype=np.float64)
    executed = np.array(report.leg_times, dtype=np.float64)
    detours: dict[int, np.ndarray] = {}
    sweep = planning = 0.0
    colliding = unplanned = 0
    for k in range(len(path) - 1):
        c0 = time.process_time()
        hit = problem.checker.leg_in_collision(path[k], path[k + 1], problem.clearance)
        sweep += time.process_time() - c0
        if not hit:
            continue
        colliding += 1
        c0 = time.process_time()
        found = plan_detour(problem.checker, path[k], path[k + 1],
                            clearance=problem.clearance, limits=problem.limits,
                            jerk=problem.arm.limits.jerk, seed=seed, params=params,
                            attempts=1)
        planning += time.process_time() - c0
        if found is None:
            unplanned += 1
            continue
        detours[k] = np.array(found.waypoints)
        planned[k], executed[k] = found.planned_time, found.executed_time
    out_cpu = dict(cpu or {})
    out_cpu["collision"] = out_cpu.get("collision", 0.0) + sweep
    out_cpu["planner"] = out_cpu.get("planner", 0.0) + planning
    counts = dict(report.counts, legs_infeasible=colliding, legs_planned=colliding,
                  legs_detoured=len(detours), legs_unplanned=unplanned)
    return dataclasses.replace(report, leg_times=executed, planned_leg_times=planned,
                               total_time=float(executed.sum()), counts=counts, cpu=out_cpu,
                               detours=detours)


def run_subset(rows: np.ndarray, indices: list[int], *, data_dir: Path, seed: int = 0,
               peers: tuple[str, ...] = PEERS, validate_dt: float = 0.01,
               peer_functions: dict[str, Callable[..., Any]] | None = None,
               alternatives: bool | None = None, stall: int | None = None,
               kicks: int | None = None, runs: int | None = None) -> dict[str, Any]:
    """Every method on one subset; a JSON-ready dict of the figures.

    ``stall``, ``kicks`` and ``runs`` set our search
    (:func:`~subtask_opt.arm.serial_problem.solve_serial_problem`: stop after ``stall`` generations
    without improvement, ``kicks`` per child, the best of ``runs`` independent runs); None:
    its defaults.

    ``alternatives``: add the +-2 pi alternatives of joints 4 and 6 (whose ranges
    exceed 2 pi) as configurations of their own (about 3x as many); None: up to
    :data:`ALTERNATIVES_MAX_HOLES` holes (the M x M leg matrix must fit in memory).

    ``peer_functions`` replaces peers by name (same contract as :mod:`subtask_opt.tour.peers`).
    """
    from subtask_opt.arm.poses import make_targets
    from subtask_opt.arm.serial_problem import SerialProblem, evaluate_tour, solve_serial_problem
    from subtask_opt.arm.trajectory import from_serial_report, validate
    from subtask_opt.cell.scene import Scene
    from subtask_opt.kinematics.ik import IKParams
    from subtask_opt.kinematics.joint_moves import joint_leg_times
    from subtask_opt.kinematics.serial import load_serial_arm
    from subtask_opt.tour.solve import MAX_KICKS, SolverParams

    stop: list[StoppingCriterion] | None = None
    if stall is not None:  # both checked before the problem is built
        stop = [NoImprovement(stall), MaxGenerations(50_000)]
    if kicks is not None:
        require_int("run_subset", "kicks", kicks, 0, MAX_KICKS)
    params = SolverParams(runs=runs, kicks=kicks)
    arm = load_serial_arm("vs060_drill", limits="robotsp")
    scene = Scene.load(data_dir / "obstacles.json")
    targets = make_targets(rows[indices], axis_step=45.0, standoff=0.01)
    home = np.radians(HOME_DEG)
    c0 = time.process_time()
    wrap = len(indices) <= ALTERNATIVES_MAX_HOLES if alternatives is None else alternatives
    problem = SerialProblem(targets, arm, home, scene=scene,
                            ik=IKParams(wrap_alternatives=bool(wrap)))
    build_cpu = time.process_time() - c0
    out: dict[str, Any] = {"holes": len(indices), "wrap_alternatives": bool(wrap),
                           "configurations_per_hole": float(problem.counts.mean()),
                           "configurations": int(problem.offsets[-1]),
                           "methods": {}}

    def record(name: str, result: Any, cpu: dict[str, float]) -> None:
        traj = from_serial_report(result)
        check = validate(traj, dt=validate_dt)
        out["methods"][name] = {
            "executed_time_s": traj.duration, "valid": check.ok,
            "violations": list(check.violations),
            # legs of the tour whose straight joint motion collides (detoured or not)
            "legs_in_collision": result.counts["legs_infeasible"],
            "legs_detoured": int(result.counts.get("legs_detoured", 0)),
            # the executed trajectory: its legs' segments swept, its samples checked
            "trajectory_legs_in_collision": check.legs_in_collision,
            "trajectory_samples_in_collision": check.collisions,
            "cpu_s": cpu,
            "cpu_total_s": float(sum(v for k, v in cpu.items() if k != "compile"))}

    ours = solve_serial_problem(problem, seed=seed, stop=stop, params=params).report
    record("ours", ours, dict(ours.cpu))
    out["methods"]["ours"]["counts"] = ours.counts
    out["methods"]["ours"]["legs_in_collision"] = evaluate_tour(
        problem, ours.order, ours.configuration_index).counts["legs_infeasible"]
    out["methods"]["ours"]["legs_detoured"] = int(ours.counts["legs_detoured"])
    out["build_cpu_s"] = build_cpu

    layers = [np.array(q) for q in problem.configurations]
    limits = problem.limits

    def leg_time(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
        return joint_leg_times(qa, qb, limits)

    for name in peers:
        fn = (peer_functions or {}).get(name) or _peer(name)
        if isinstance(fn, str):
            out["methods"][name] = {"unavailable": fn}
            continue
        c0 = time.process_time()
        extra = 0.0
        with compile_seconds() as compiled:  # a peer's first call may load kernels
            if name == "robotsp":
                order, choice = fn(targets.points, layers, home, limits.velocity, leg_time)
            elif name == "tsp_cspace":
                m0 = time.process_time()
                manip = _manipulability(arm, layers)
                extra = time.process_time() - m0
                order, choice = fn(layers, home, manip, leg_time)
            else:
                try:
                    order, choice = fn(layers, home, leg_time, seed=seed)
                except ParameterError as exc:  # e.g. past the GTSP peer's node cap
                    out["methods"][name] = {"unavailable": str(exc)}
                    continue
        loading = min(compiled[0], time.process_time() - c0 - extra)
        search = time.process_time() - c0 - extra - loading
        cpu = {"ik": problem.cpu["ik"], "collision": problem.cpu["collision"],
               "matrix": problem.cpu["matrix"] + extra, "search": search,
               "compile": problem.cpu["compile"] + loading}
        straight = evaluate_tour(problem, order, choice, seed=seed, cpu=cpu)
        record(name, straight, cpu)
        if name == "robotsp":  # and RoboTSP's last step: plan the colliding legs
            after = plan_after(problem, straight, seed=seed, params=problem.detour,
                               cpu={**cpu, "collision": problem.cpu["collision"]})
            record("robotsp_planned", after, after.cpu)
            out["methods"]["robotsp_planned"]["counts"] = after.counts
    return out


def run(data_dir: str | Path, *, sizes: list[int] | None = None, seed: int = 0,
        peers: tuple[str, ...] = PEERS,
        peer_functions: dict[str, Callable[..., Any]] | None = None,
        stall: int | None = None, kicks: int | None = None,
        runs: int | None = None) -> dict[str, Any]:
    """The benchmark over RoboTSP's subsets (``sizes``: which, default all); ``stall``,
    ``kicks`` and ``runs`` as in :func:`run_subset`."""
    data_dir = Path(data_dir)
    rows, subsets, published = _load(data_dir)
    chosen = sizes or [int(k) for k in subsets]
    report: dict[str, Any] = {"robot": "vs060_drill (frames reconstructed from RoboTSP's files)",
                              "seed": seed, "stall": stall, "kicks": kicks, "runs": runs,
                              "subsets": {}}
    for size in chosen:
        if str(size) not in subsets:
            raise InputDataError(f"no subset of {size} holes; have {sorted(subsets)}")
        report["subsets"][str(size)] = run_subset(rows, subsets[str(size)], data_dir=data_dir,
                                                  seed=seed, peers=peers,
                                                  peer_functions=peer_functions,
                                                  stall=stall, kicks=kicks, runs=runs)
    report["published"] = {m: dict(zip(published["number_of_targets"], v, strict=False))
                           for m, v in published.get("execution_time_s", {}).items()}
    return report


def table(report: dict[str, Any]) -> str:
    """The report as text: one row per subset and method."""
    search = ", ".join(f"{k} {report[k]}" for k in ("stall", "kicks", "runs")
                       if report.get(k) is not None) or "default search"
    lines = [f"RoboTSP drilling benchmark on {report['robot']}, seed {report['seed']}, "
             f"{search}",
             f"{'holes':>5} {'method':<15} {'exec s':>8} {'valid':>5} {'coll':>4} {'det':>3} "
             f"{'traj':>4} {'IK s':>6} {'coll s':>6} {'matrix s':>8} {'search s':>8} "
             f"{'plan s':>6} {'compile s':>9} {'conf/hole':>9} {'vs robotsp':>10}",
             "  (coll: tour legs whose straight motion collides; det: legs driven through "
             "planned waypoints; traj: legs of the executed trajectory in collision)"]
    for size, sub in report["subsets"].items():
        ref = sub["methods"].get("robotsp", {}).get("executed_time_s")
        for name, m in sub["methods"].items():
            if "unavailable" in m:
                lines.append(f"{size:>5} {name:<15} unavailable: {m['unavailable']}")
                continue
            c = m["cpu_s"]
            ratio = f"{m['executed_time_s'] / ref:.3f}x" if ref else "-"
            lines.append(f"{size:>5} {name:<15} {m['executed_time_s']:8.3f} "
                         f"{'yes' if m['valid'] else 'NO':>5} {m['legs_in_collision']:>4} "
                         f"{m.get('legs_detoured', 0):>3} "
                         f"{m.get('trajectory_legs_in_collision') or 0:>4} "
                         f"{c.get('ik', 0):6.2f} {c.get('collision', 0):6.2f} "
                         f"{c.get('matrix', 0):8.2f} {c.get('search', 0):8.2f} "
                         f"{c.get('planner', 0):6.2f} {c.get('compile', 0):9.2f} "
                         f"{sub['configurations_per_hole']:9.1f} {ratio:>10}")
    lines.append("published (RoboTSP's own robot model, BiRRT legs; context only):")
    for method, per in report["published"].items():
        cells = ", ".join(f"{k}: {'-' if v is None else f'{v:.1f} s'}" for k, v in per.items())
        lines.append(f"  {method}: {cells}")
    return "\n".join(lines)


__all__ = ["PEERS", "plan_after", "run", "run_subset", "table"]
