"""Does the tour a time model picks run as fast as the model says, on the real arm?

For square20 and random30 (``--instances`` generator seeds) on both robots,
the tour is optimised under each time model - ``paper``, ``trapezoid`` (the
Cartesian models, one elbow branch), ``line`` and ``joint`` (joint-aware, the
elbow configuration of each subtask chosen with the order) - and then executed
as a trajectory that respects the joint limits
(:func:`subtask_opt.arm.trajectory.build_trajectory`): the Cartesian models' straight
lines are driven as fast as the joint and Cartesian limits allow (a joint move
where the line is impossible), the joint-aware models exactly as timed. Every
trajectory is checked by the validator.

Reported per robot, case and model: the predicted tour time, the executed
time, their ratio, and the executed time relative to the fastest model's tour
on the same instance; for the Cartesian models also the share of the tour's
legs whose straight line, driven at the model's Cartesian trapezoid, would
exceed a joint limit (impossible line or a joint speed above its limit).

Jerk limits are on wherever the robot has them (planar_2r: 100 and 150 rad/s^3;
asr_twodof has none): joint moves and straight lines are jerk-limited, the
``line`` model times its lines that way, and the validator checks the jerk by
finite differences (column "jerk": the largest |jerk| / limit, "-" when the
robot has no jerk limits).

    python benchmarks/fidelity.py [--instances 10] [--seed 0] [--json out/fidelity.json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np

from subtask_opt import builtin_case, solve
from subtask_opt.arm.planar_problem import PlanarProblem
from subtask_opt.arm.trajectory import build_trajectory, validate
from subtask_opt.base.progress import progress_bar
from subtask_opt.kinematics.planar import load_planar_arm

ROBOTS = ("planar_2r", "asr_twodof")
MODELS = ("paper", "trapezoid", "line", "joint")


def _tour_leg_share(problem: PlanarProblem, order: np.ndarray) -> tuple[float, float]:
    """Shares of the tour's legs whose straight line is impossible / over a joint speed."""
    check = problem.timing.leg_check
    a, b = order, np.roll(order, -1)
    impossible = check.outside_annulus[a, b]
    over = (check.speed_ratio[a, b] > 1.0) & ~impossible
    return float(impossible.mean()), float(over.mean())


def run_instance(robot: str, case: str, instance: int, seed: int, arm) -> list[dict]:
    subtasks = builtin_case(case, arm, seed=instance)
    rows = []
    for model in MODELS:
        configurations = "optimize" if model in ("line", "joint") else "fixed"
        problem = PlanarProblem(subtasks, arm, time_model=model,
                                configurations=configurations)
        result = solve(problem, seed=seed)
        trajectory = build_trajectory(result)
        report = validate(trajectory, dt=2e-3)
        row = {
            "robot": robot, "case": case, "instance": instance, "model": model,
            "predicted_s": result.total_time, "executed_s": trajectory.duration,
            "valid": report.ok, "violations": list(report.violations),
            "max_jerk_ratio": (None if report.max_jerk_ratio is None
                               else max(report.max_jerk_ratio)),
            "elbow_changes": result.report.configuration_changes,
            "joint_moves": sum(leg.kind == "joint" for leg in trajectory.legs),
        }
        if model in ("paper", "trapezoid"):
            row["share_impossible"], row["share_overspeed"] = _tour_leg_share(problem,
                                                                                result.order)
            lc = problem.timing.leg_check
            row["all_pairs_impossible"] = lc.share_infeasible
            row["all_pairs_overspeed"] = lc.share_overspeed
        rows.append(row)
    best = min(r["executed_s"] for r in rows)
    for r in rows:
        r["vs_best"] = r["executed_s"] / best
    return rows


def summarise(rows: list[dict]) -> list[dict]:
    table = []
    for robot in ROBOTS:
        for case in ("square20", "random30"):
            for model in MODELS:
                sel = [r for r in rows if (r["robot"], r["case"], r["model"]) == (robot, case,
                                                                                  model)]
                if not sel:
                    continue
                entry = {
                    "robot": robot, "case": case, "model": model, "instances": len(sel),
                    "predicted_s": statistics.mean(r["predicted_s"] for r in sel),
                    "executed_s": statistics.mean(r["executed_s"] for r in sel),
                    "executed_over_predicted": statistics.mean(
                        r["executed_s"] / r["predicted_s"] for r in sel),
                    "vs_best": statistics.mean(r["vs_best"] for r in sel),
                    "fastest": sum(r["vs_best"] == 1.0 for r in sel),
                    "valid": sum(r["valid"] for r in sel),
                    "max_jerk_ratio": (None if sel[0]["max_jerk_ratio"] is None
                                       else max(r["max_jerk_ratio"] for r in sel)),
                }
                if "share_impossible" in sel[0]:
                    entry["share_impossible"] = statistics.mean(r["share_impossible"]
                                                                for r in sel)
                    entry["share_overspeed"] = statistics.mean(r["share_overspeed"] for r in sel)
                    entry["all_pairs_impossible"] = statistics.mean(
                        r["all_pairs_impossible"] for r in sel)
                    entry["all_pairs_overspeed"] = statistics.mean(
                        r["all_pairs_overspeed"] for r in sel)
                table.append(entry)
    return table


def print_table(table: list[dict]) -> None:
    head = (f"{'robot':<11} {'case':<9} {'model':<9} {'n':>3} {'predicted':>10} {'executed':>10} "
            f"{'exec/pred':>9} {'vs best':>8} {'fastest':>7} {'valid':>5} {'jerk':>6}  "
            f"{'tour legs past a joint limit (impossible + overspeed)':<40}")
    print(head)
    print("-" * len(head))
    for e in table:
        share = ""
        jerk = "-" if e["max_jerk_ratio"] is None else f"{e['max_jerk_ratio']:.3f}"
        if "share_impossible" in e:
            share = (f"{100 * (e['share_impossible'] + e['share_overspeed']):5.1f}% "
                     f"({100 * e['share_impossible']:.1f}% + {100 * e['share_overspeed']:.1f}%);"
                     f" all pairs {100 * e['all_pairs_impossible']:.0f}% impossible, "
                     f"{100 * e['all_pairs_overspeed']:.0f}% of the rest overspeed")
        print(f"{e['robot']:<11} {e['case']:<9} {e['model']:<9} {e['instances']:>3} "
              f"{e['predicted_s']:>9.3f}s {e['executed_s']:>9.3f}s "
              f"{e['executed_over_predicted']:>9.3f} {e['vs_best']:>8.3f} "
              f"{e['fastest']:>7} {e['valid']:>5} {jerk:>6}  {share}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--instances", type=int, default=10,
                        help="random30 generator seeds (default 10)")
    parser.add_argument("--seed", type=int, default=0, help="solver seed (default 0)")
    parser.add_argument("--json", metavar="OUT.json", help="write every run and the table")
    args = parser.parse_args(argv)
    if args.instances < 1:
        parser.error(f"--instances must be >= 1, got {args.instances}")
    start = time.perf_counter()
    jobs = [(robot, "square20", 0) for robot in ROBOTS] + [
        (robot, "random30", k) for robot in ROBOTS for k in range(args.instances)]
    arms = {robot: load_planar_arm(robot) for robot in ROBOTS}
    rows: list[dict] = []
    with progress_bar(True, total=len(jobs), desc="instances") as bar:
        for robot, case, instance in jobs:
            rows.extend(run_instance(robot, case, instance, args.seed, arms[robot]))
            bar.update(1)
    table = summarise(rows)
    print(f"fidelity: tours optimised under each model, executed within the joint limits "
          f"(mean over instances; square20 is one instance; {time.perf_counter() - start:.0f} s)")
    print_table(table)
    invalid = [r for r in rows if not r["valid"]]
    print(f"trajectories validated: {len(rows) - len(invalid)} of {len(rows)} within all "
          "joint limits (position, velocity, acceleration; jerk where the robot has limits)")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps({"table": table, "runs": rows}, indent=1))
        print(f"wrote {args.json}")
    return 0 if not invalid else 1


if __name__ == "__main__":
    raise SystemExit(main())
