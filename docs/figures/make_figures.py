"""Regenerate the sequencing figures of the docs with the public API.

    python docs/figures/make_figures.py [--out docs/figures] [--seed 0]

Writes ``sequencing_25.png`` (a 5 x 5 grid part inside planar_2r's reachable
ring, ``line`` model), ``sequencing_random30.png`` (the built-in random30 case,
``joint`` model) and ``sequencing_100.png`` (100 random reachable points,
``joint`` model). Each run's solver seed is ``--seed``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

from subtask_opt import builtin_case, solve
from subtask_opt.arm.planar_problem import PlanarProblem  # noqa: E402
from subtask_opt.arm.targets import Targets
from subtask_opt.arm.tasks import random_subtasks  # noqa: E402
from subtask_opt.kinematics.planar import load_planar_arm
from subtask_opt.plotting.sequencing import save_solution_figure  # noqa: E402


def grid_part(n_side: int = 5) -> Targets:
    """An n x n lattice at x in [0.22, 0.50] m, y in [-0.14, 0.14] m (planar_2r reaches all)."""
    xs = np.linspace(0.22, 0.50, n_side)
    ys = np.linspace(-0.14, 0.14, n_side)
    pts = np.array([(x, y) for y in ys for x in xs])
    return Targets(pts, name=f"grid{n_side * n_side}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=str(Path(__file__).parent), help="output folder")
    parser.add_argument("--seed", type=int, default=0, help="solver seed (default 0)")
    args = parser.parse_args(argv)
    out = Path(args.out)
    arm = load_planar_arm("planar_2r")
    runs = [
        ("sequencing_25.png", grid_part(5), "line"),
        ("sequencing_random30.png", builtin_case("random30", arm, seed=0), "joint"),
        ("sequencing_100.png", random_subtasks(arm, 100, seed=1, name="random100"), "joint"),
    ]
    for name, subtasks, model in runs:
        problem = PlanarProblem(subtasks, arm, time_model=model, configurations="optimize")
        result = solve(problem, seed=args.seed)
        path = save_solution_figure(result, problem, out / name)
        print(f"wrote {path}: {result.total_time:.3f} s, {result.generations} generations")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
