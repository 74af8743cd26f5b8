"""RoboTSP's drilling benchmark: ours beside RoboTSP's method, TSP C-space and LKH's GTSP.

``robotsp_planned`` is RoboTSP's whole pipeline: its tour, then every straight leg that
collides with the panel or the pedestal planned after sequencing (OMPL RRTConnect +
simplification, :func:`subtask_opt.papers.robotsp.plan_after`); ours plans the legs its
best tours use lazily inside the search. Each row's trajectory is validated (samples and
every joint segment swept against the boxes: ``traj`` counts its legs in collision).

Runs :func:`subtask_opt.papers.robotsp.run` on ``../shared/data/robotsp``
(every subset, or ``--sizes 25,50``) and prints the table. The peers come from
``subtask_opt.tour.peers``; while that module is missing, ``--stand-in`` runs
a minimal re-implementation of RoboTSP's method written here (Euclidean 2-opt
on the hole positions from a nearest-neighbour start, then a layered shortest
path through the configurations in that order with the max-joint-difference
metric weighted by 1/v_max, home to home), so the ratio can be measured.

    python benchmarks/robotsp.py [--sizes 25,50] [--seed 0] [--stall S] [--kicks K]
                                 [--runs R] [--json out.json] [--stand-in]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from subtask_opt.base.errors import SubtaskOptError
from subtask_opt.papers.robotsp import run, table

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "robotsp"


def _two_opt(points: np.ndarray) -> np.ndarray:
    """A closed Euclidean tour: nearest neighbour from point 0, then 2-opt to a local optimum."""
    n = len(points)
    d = np.linalg.norm(points[:, None] - points[None], axis=2)
    tour = [0]
    left = set(range(1, n))
    while left:
        nxt = min(left, key=lambda j: d[tour[-1], j])
        tour.append(nxt)
        left.remove(nxt)
    t = np.array(tour)
    improved = True
    while improved:
        improved = False
        for i in range(n - 1):
            for j in range(i + 2, n if i > 0 else n - 1):
                a, b, c, e = t[i], t[i + 1], t[j], t[(j + 1) % n]
                if d[a, c] + d[b, e] < d[a, b] + d[c, e] - 1e-12:
                    t[i + 1:j + 1] = t[i + 1:j + 1][::-1]
                    improved = True
    return t


def robotsp_stand_in(positions, layers, home, vmax, leg_time):  # noqa: ANN001, ANN201
    """RoboTSP's method (stand-in; same contract as subtask_opt.tour.peers.robotsp_method)."""
    cycle = _two_opt(np.asarray(positions))
    # open the cycle next to home: start at the hole whose best configuration is nearest
    start_cost = [np.min(np.max(np.abs(layers[i] - home) / vmax, axis=1)) for i in cycle]
    k = int(np.argmin(start_cost))
    order = np.roll(cycle, -k)
    # layered shortest path, metric max_j |dq_j| / vmax_j, home -> layers -> home
    cost = np.max(np.abs(layers[order[0]] - home) / vmax, axis=1)
    preds = []
    for a, b in zip(order[:-1], order[1:], strict=True):
        metric = np.max(np.abs(layers[a][:, None, :] - layers[b][None]) / vmax, axis=2)
        total = cost[:, None] + metric
        preds.append(np.argmin(total, axis=0))
        cost = total.min(axis=0)
    cost = cost + np.max(np.abs(layers[order[-1]] - home) / vmax, axis=1)
    c = int(np.argmin(cost))
    choice = np.zeros(len(order), dtype=np.int64)
    for k in range(len(order) - 1, -1, -1):
        choice[order[k]] = c
        if k > 0:
            c = int(preds[k - 1][c])
    return order, choice


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default=None, help="comma-separated subset sizes (default all)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--stall", type=int, default=None,
                    help="our search stops after this many generations without improvement "
                         "(default: SolverParams.default_stop)")
    ap.add_argument("--kicks", type=int, default=None,
                    help="kicks per child of our search (default: make_aux's)")
    ap.add_argument("--runs", type=int, default=None,
                    help="independent runs of our search, the best kept (default 1)")
    ap.add_argument("--json", default=None)
    ap.add_argument("--data", default=str(DATA))
    ap.add_argument("--stand-in", action="store_true",
                    help="use this script's RoboTSP method where subtask_opt.tour.peers lacks it")
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")] if args.sizes else None
    peers = {"robotsp": robotsp_stand_in} if args.stand_in else None
    try:
        report = run(args.data, sizes=sizes, seed=args.seed, peer_functions=peers,
                     stall=args.stall, kicks=args.kicks, runs=args.runs)
    except SubtaskOptError as exc:
        print(f"robotsp.py: error: {exc}", file=sys.stderr)
        return 2
    if args.stand_in:
        report["note"] = "robotsp column: the stand-in of benchmarks/robotsp.py"
    print(table(report))
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1))
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
