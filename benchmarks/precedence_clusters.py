"""Precedence with configurations chosen: the pinned clustered kind against exact optima.

Planar arms (``planar_2r``, ``asr_twodof``), the default ``joint`` time model with the
elbows chosen (a generalised TSP of two configurations per subtask), random subtasks
(:func:`subtask_opt.arm.tasks.random_subtasks`, seeds ``--set-seed + k``) and N/2 random
acyclic precedence pairs, closed tours and open paths (free end). The optimum comes from
the clustered Held-Karp programme (:func:`subtask_opt.tour.exact.clustered_held_karp`,
N <= 12) or the arc MILP (:func:`subtask_opt.tour.exact.milp_pinned_clustered`, larger N,
``--milp-time-limit``; an instance it does not prove is judged against the best answer
known and flagged). Ours: ``solve()`` with its default stop from seeds 0..``--seeds - 1``;
"before": what ``solve`` did before the pinned clustered kind (the order searched by the
pinned kind on the cheapest legs between subtasks, the elbows of that order decoded
after it). A run hits when it is within a relative 1e-9 of the optimum. Times are wall
seconds per solve after JIT warm-up (shared machine: compare within one run).

    python benchmarks/precedence_clusters.py [--sizes 8 12 16] [--sets 3] [--seeds 5]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np

from subtask_opt.arm.planar_problem import PlanarProblem, solve
from subtask_opt.arm.tasks import random_subtasks
from subtask_opt.base.errors import SubtaskOptError
from subtask_opt.kinematics.planar import load_planar_arm
from subtask_opt.tour.configurations import best_configurations
from subtask_opt.tour.constraints import TourConstraints, canonical, transform_tensor
from subtask_opt.tour.exact import clustered_held_karp, milp_pinned_clustered
from subtask_opt.tour.problem import MatrixProblem


def _pairs(rng: np.random.Generator, n: int) -> list[tuple[int, int]]:
    rank = rng.permutation(n)
    out = set()
    while len(out) < n // 2:
        a, b = (int(v) for v in rng.choice(n, 2, replace=False))
        if rank[a] > rank[b]:
            a, b = b, a
        if b != 0:
            out.add((a, b))
    return sorted(out)


def _optimum(tensor: np.ndarray, pairs, limit: float) -> tuple[float, bool]:
    """(optimum, proven) of the closed tour from cluster 0 over ``tensor`` keeping pairs."""
    n = tensor.shape[0]
    if n <= 13:
        rest = list(range(1, n))
        legs = tensor[np.ix_(rest, [0, 1], rest, [0, 1])].reshape(2 * n - 2, 2 * n - 2)
        inner = np.array([(a - 1, b - 1) for a, b in pairs if a != 0],
                         dtype=np.int64).reshape(-1, 2)
        best = math.inf
        for c0 in range(2):
            best = min(best, clustered_held_karp(
                legs, np.arange(0, 2 * n - 1, 2), tensor[0, c0][rest].reshape(-1),
                tensor[rest, :, 0, c0].reshape(-1), pairs=inner))
        return best, True
    try:
        cost, _, _ = milp_pinned_clustered(tensor.reshape(2 * n, 2 * n),
                                           np.repeat(np.arange(n), 2), 0, -1, pairs,
                                           time_limit=limit)
        return cost, True
    except SubtaskOptError:
        return math.inf, False


def _before(problem, c: TourConstraints, tensor: np.ndarray, seed: int) -> float:
    """The search before the pinned clustered kind: the pinned kind on the cheapest legs
    between subtasks, then the elbows of that order decoded."""
    dist = np.min(tensor, axis=(1, 3))
    np.fill_diagonal(dist, 0.0)
    r = solve(MatrixProblem(dist), seed=seed, constraints=c)
    order = np.asarray(r.order)
    return best_configurations(order, tensor)[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[8, 12, 16])
    parser.add_argument("--sets", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--set-seed", type=int, default=7000)
    parser.add_argument("--robots", nargs="+", default=["planar_2r", "asr_twodof"])
    parser.add_argument("--milp-time-limit", type=float, default=300.0)
    args = parser.parse_args()
    print(f"{'robot':>11} {'N':>3} {'set':>5} {'tour':>6} {'optimum':>10} {'proof':>6} "
          f"{'ours hits':>9} {'median s':>8} {'before hits':>11} {'before worst':>12}")
    total = hits_all = 0
    for robot in args.robots:
        arm = load_planar_arm(robot)
        for n in args.sizes:
            for k in range(args.sets):
                set_seed = args.set_seed + 100 * n + k
                sub = random_subtasks(arm, n, seed=set_seed)
                problem = PlanarProblem(sub, arm)
                base = np.asarray(problem.tour_problem.costs)
                pairs = _pairs(np.random.default_rng(set_seed), n)
                for tour in ("closed", "open"):
                    c = TourConstraints(tour=tour, precedence=pairs)
                    canon = canonical(problem.matrix, c, default_start=0)
                    tensor = transform_tensor(base, canon)
                    optimum, proven = _optimum(tensor, pairs, args.milp_time_limit)
                    ours, seconds = [], []
                    for seed in range(args.seeds):
                        t0 = time.perf_counter()
                        r = solve(problem, seed=seed, constraints=c)
                        seconds.append(time.perf_counter() - t0)
                        pos = {int(v): i for i, v in enumerate(r.order)}
                        assert all(pos[a] < pos[b] for a, b in pairs)
                        ours.append(r.total_time)
                    before = [_before(problem, c, tensor, seed) for seed in range(args.seeds)]
                    if not proven:
                        optimum = min(ours + before)
                    hit = sum(v <= optimum * (1 + 1e-9) for v in ours)
                    total += len(ours)
                    hits_all += hit
                    hit_b = sum(v <= optimum * (1 + 1e-9) for v in before)
                    worst_b = 100 * (max(before) / optimum - 1)
                    print(f"{robot:>11} {n:>3} {k:>5} {tour:>6} {optimum:>10.5f} "
                          f"{'yes' if proven else 'no':>6} {hit:>4}/{len(ours):<4} "
                          f"{statistics.median(seconds):>8.3f} {hit_b:>6}/{len(before):<4} "
                          f"{worst_b:>+11.3f}%", flush=True)
    print(f"ours at the optimum in {hits_all} of {total} runs")


if __name__ == "__main__":
    main()
