"""A cell where straight legs collide: executed time with detours vs ``--no-detours``.

A UR5 drills two groups of holes in a curved sheet (an STL written here) with a drill box
on ``tool0`` (TCP 0.15 m out), a table box under everything and an STL pillar standing on
the sheet between the groups, as tall as the arm's reach over it. Every straight joint
move from one group to the other sweeps the drill or the wrist through the pillar, so
without detours (``detours=False``, what ``solve --no-detours`` sets) the tour must cross
by legs that go around it within one straight joint line (from a home or through
configurations chosen for that), while with detours the search plans the crossing legs
(OMPL RRTConnect, :mod:`subtask_opt.cell.detour`) and takes them when they are faster.

For each seed both variants are solved on the same problem data; each executed
trajectory is validated (:func:`subtask_opt.validate`: samples and every joint segment
swept against the cell, duration against ``total_time``). Printed: a table per seed and
the medians; ``--json`` writes every figure. The detoured tour must be strictly shorter
(exit 1 otherwise).

    python benchmarks/detour_cell.py [--seeds 0,1,2] [--holes-per-row 3] [--plans 40]
                                     [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

HOME_DEG = (0.0, -100.0, 100.0, -90.0, -90.0, 0.0)
PILLAR = (0.5, 0.0, 0.55)  # x, y, height (m)
SHEET = {"center": (0.5, 0.0, 0.05), "curvature": 0.6}


def write_cell(folder: Path, per_row: int) -> tuple[Path, Path]:
    """The scene file (sheet and pillar STLs, table box, drill on tool0) and the holes."""
    from subtask_opt.cell.meshes import box_triangles, curved_sheet, write_stl

    write_stl(folder / "sheet.stl", *curved_sheet(SHEET["center"], (0.3, 0.8),
                                                  SHEET["curvature"]))
    write_stl(folder / "pillar.stl", *box_triangles([0.04, 0.04, PILLAR[2] / 2]))
    scene = {
        "note": "benchmarks/detour_cell.py: two groups of holes, a pillar between them",
        "boxes": [{"name": "table", "center": [0.3, 0.0, -0.03],
                   "half_extents": [0.7, 0.7, 0.02]}],
        "meshes": [{"name": "sheet", "file": "sheet.stl"},
                   {"name": "pillar", "file": "pillar.stl",
                    "position": [PILLAR[0], PILLAR[1], PILLAR[2] / 2]}],
        "tool": {"frame": "tool0", "tcp": {"xyz": [0, 0, 0.15]},
                 "boxes": [{"name": "drill", "center": [0, 0, 0.065],
                            "half_extents": [0.02, 0.02, 0.065]}]}}
    (folder / "cell.json").write_text(json.dumps(scene))
    rows = ["x,y,z,dx,dy,dz"]
    ys = np.linspace(0.2, 0.34, per_row)
    for y in np.concatenate([-ys[::-1], ys]):
        for x in (0.45, 0.55):
            cx, cz = SHEET["center"][0], SHEET["center"][2]
            normal = np.array([-2 * SHEET["curvature"] * (x - cx), 0.0, 1.0])
            d = -normal / np.linalg.norm(normal)  # into the sheet
            rows.append(f"{x},{y:.4f},{cz + SHEET['curvature'] * (x - cx) ** 2:.6f},"
                        f"{d[0]:.6f},{d[1]},{d[2]:.6f}")
    (folder / "holes.csv").write_text("\n".join(rows) + "\n")
    return folder / "cell.json", folder / "holes.csv"


def solve_variant(scene: Path, holes: Path, *, detours: bool, seed: int,
                  plans: int) -> dict[str, Any]:
    """One solve of the cell; its figures (a JSON-ready dict)."""
    import subtask_opt as so
    from subtask_opt.arm.problem import ArmProblem, load_robot, load_targets
    from subtask_opt.cell.detour import DetourParams

    targets = load_targets(holes, standoff=0.05, axis_step=45.0)
    c0 = time.process_time()
    problem = ArmProblem(targets, load_robot("ur5"), home=np.radians(HOME_DEG), scene=scene,
                         detours=detours,
                         detour=DetourParams(max_plans=plans) if detours else None)
    build = time.process_time() - c0
    result = so.solve(problem, seed=seed)
    trajectory = so.trajectory(result)
    check = so.validate(trajectory)
    counts = result.report.counts
    cpu = dict(result.report.cpu)
    return {"executed_time_s": float(result.total_time),
            "trajectory_duration_s": float(trajectory.duration),
            "valid": bool(check.ok), "violations": list(check.violations),
            "trajectory_legs_in_collision": check.legs_in_collision,
            "trajectory_samples_in_collision": check.collisions,
            "legs_checked": counts["legs_checked"], "legs_infeasible": counts["legs_infeasible"],
            "legs_planned": counts["legs_planned"], "legs_detoured": counts["legs_detoured"],
            "search_rounds": counts["search_rounds"],
            "cpu_s": {"build": build, **cpu},
            "cpu_total_s": build + float(sum(v for k, v in cpu.items() if k != "compile"))}


def run(seeds: list[int], per_row: int, plans: int) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as tmp:
        scene, holes = write_cell(Path(tmp), per_row)
        report: dict[str, Any] = {"holes": 4 * per_row, "plan_budget": plans, "runs": {}}
        for seed in seeds:
            report["runs"][str(seed)] = {
                name: solve_variant(scene, holes, detours=flag, seed=seed, plans=plans)
                for name, flag in (("detours", True), ("no_detours", False))}
    runs = report["runs"].values()
    report["median"] = {name: {key: statistics.median(r[name][key] for r in runs)
                               for key in ("executed_time_s", "cpu_total_s", "legs_detoured")}
                        for name in ("detours", "no_detours")}
    return report


def table(report: dict[str, Any]) -> str:
    lines = [f"detour cell: UR5, {report['holes']} holes in two groups, a pillar between; "
             f"plan budget {report['plan_budget']} legs",
             f"{'seed':>4} {'variant':<11} {'exec s':>8} {'valid':>5} {'traj':>4} "
             f"{'checked':>7} {'coll':>4} {'planned':>7} {'det':>3} {'coll s':>6} "
             f"{'search s':>8} {'plan s':>6} {'compile s':>9} {'cpu s':>6}"]
    for seed, variants in report["runs"].items():
        for name, m in variants.items():
            c = m["cpu_s"]
            lines.append(f"{seed:>4} {name:<11} {m['executed_time_s']:8.3f} "
                         f"{'yes' if m['valid'] else 'NO':>5} "
                         f"{m['trajectory_legs_in_collision'] or 0:>4} {m['legs_checked']:>7} "
                         f"{m['legs_infeasible']:>4} {m['legs_planned']:>7} "
                         f"{m['legs_detoured']:>3} {c.get('collision', 0):6.2f} "
                         f"{c.get('search', 0):8.2f} {c.get('planner', 0):6.2f} "
                         f"{c.get('compile', 0):9.2f} {m['cpu_total_s']:6.2f}")
    med = report["median"]
    ratio = med["detours"]["executed_time_s"] / med["no_detours"]["executed_time_s"]
    lines.append(f"median executed time: detours {med['detours']['executed_time_s']:.3f} s, "
                 f"no detours {med['no_detours']['executed_time_s']:.3f} s ({ratio:.3f}x); "
                 f"median CPU {med['detours']['cpu_total_s']:.2f} s vs "
                 f"{med['no_detours']['cpu_total_s']:.2f} s (compile time apart)")
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2", help="comma-separated seeds")
    ap.add_argument("--holes-per-row", type=int, default=3,
                    help="holes per row; 4 rows (two per group)")
    ap.add_argument("--plans", type=int, default=40, help="most legs one solve plans")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    try:
        seeds = [int(s) for s in args.seeds.split(",")]
    except ValueError:
        print(f"detour_cell.py: error: --seeds must be integers, got {args.seeds!r}",
              file=sys.stderr)
        return 2
    if not 1 <= args.holes_per_row <= 20 or not 1 <= args.plans <= 10_000:
        print("detour_cell.py: error: --holes-per-row must be in [1, 20] and --plans in "
              "[1, 10000]", file=sys.stderr)
        return 2
    report = run(seeds, args.holes_per_row, args.plans)
    print(table(report))
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1))
        print(f"wrote {args.json}")
    shorter = all(r["detours"]["executed_time_s"] < r["no_detours"]["executed_time_s"]
                  for r in report["runs"].values())
    valid = all(m["valid"] for r in report["runs"].values() for m in r.values())
    if not (shorter and valid):
        print("detour_cell.py: FAILED: detours not strictly shorter on every seed, or an "
              "invalid trajectory", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
