"""How the default solve scales: random Euclidean instances of N = 100 ... 3200 nodes.

For each N, ``--seeds`` instances (uniform points in the unit square, distances
as a dense matrix; with ``--asymmetric`` each ordered pair also gets a random
offset of up to ``0.2 / sqrt(N)``, about a third of a typical tour edge, so the
matrix is asymmetric and the solve takes its any-costs search) are solved
with the default parameters and the default stop
(:meth:`subtask_opt.SolverParams.default_stop`), one seed each. Printed per N:
median CPU time of ``MatrixProblem`` (matrix checks), of ``solve`` (the candidate
lists, an O(N^2) argpartition or alpha-nearness, and the search) and their sum,
numba's compiling or loading of kernels inside them apart (``compile s``: the
warm-up at N = 20 leaves e.g. the alpha-nearness kernels to the first N >= 100), the
median number of generations, the tour length over sqrt(N) (about 0.7124 for
optimal tours of many uniform points, the Beardwood-Halton-Hammersley constant;
a yardstick where there is no bound) and against the Held-Karp bound where it is
computed (N <= ``bound_max_nodes``). Then the exponent b of a
least-squares fit time = a N^b over all N, for the solve and the build.

Times are process CPU times (a busy machine's waiting left out); the machine may be
shared and busy (the load average is printed), so compare within one run.

    python benchmarks/growth.py [--sizes 100,200,400,800,1600,3200] [--seeds 3] [--asymmetric]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from subtask_opt import solve
from subtask_opt._kernel_cache import compile_seconds
from subtask_opt.tour.problem import MatrixProblem


def _instance(n: int, seed: int, asymmetric: bool = False) -> np.ndarray:
    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    m = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))
    if asymmetric:
        m += rng.random((n, n)) * (0.2 / np.sqrt(n))
        np.fill_diagonal(m, 0.0)
    return m


def fit_exponent(sizes: list[int], times: list[float]) -> float:
    """Slope of log(time) against log(N) (least squares)."""
    slope, _ = np.polyfit(np.log(sizes), np.log(times), 1)
    return float(slope)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="100,200,400,800,1600,3200",
                        help="comma-separated node counts (default 100,...,3200)")
    parser.add_argument("--seeds", type=int, default=3, help="instances per size (default 3)")
    parser.add_argument("--asymmetric", action="store_true",
                        help="random per-pair offsets: asymmetric matrices")
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    solve(MatrixProblem(_instance(20, 0, args.asymmetric)), seed=0)  # JIT warm-up
    print(f"{'N':>6} {'build s':>8} {'solve s':>8} {'total s':>8} {'compile s':>9} "
          f"{'gens':>6} {'len/sqrtN':>9} {'gap to bound':>12}")
    builds, solves = [], []
    for n in sizes:
        b, s, c, g, gaps, lengths = [], [], [], [], [], []
        for seed in range(args.seeds):
            m = _instance(n, 1000 * n + seed, args.asymmetric)
            t0 = time.process_time()
            with compile_seconds() as built:
                problem = MatrixProblem(m)
            t1 = time.process_time()
            with compile_seconds() as solved:
                result = solve(problem, seed=seed)
            t2 = time.process_time()
            b.append(t1 - t0 - built[0])
            s.append(t2 - t1 - solved[0])
            c.append(built[0] + solved[0])
            g.append(result.generations)
            lengths.append(result.total_time / np.sqrt(n))
            if result.lower_bound is not None:
                gaps.append(result.total_time / result.lower_bound - 1)
        builds.append(statistics.median(b))
        solves.append(statistics.median(s))
        gap = f"{100 * statistics.median(gaps):11.2f}%" if gaps else f"{'-':>12}"
        print(f"{n:>6} {builds[-1]:8.3f} {solves[-1]:8.3f} {builds[-1] + solves[-1]:8.3f} "
              f"{max(c):9.3f} {statistics.median(g):6.0f} {statistics.median(lengths):9.4f} "
              f"{gap}", flush=True)
    print(f"fitted exponent (time ~ N^b): solve b = {fit_exponent(sizes, solves):.2f}, "
          f"build b = {fit_exponent(sizes, builds):.2f}")


if __name__ == "__main__":
    main()
