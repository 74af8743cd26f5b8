"""Which reading of the sequencing paper's micro-GA reproduces its generation counts?

The paper (seed 002, section III-2 and IV) reports the optimum at about
generation 500 for 20 lattice subtasks and about 800 for 30 random ones. Its
micro-GA leaves several choices open; each reading below is one combination of
them, expressed as the paper preset's loop (:class:`subtask_opt.ga.config.GAConfig`
passed as ``SolverParams(preset="paper", paper_loop=...)``):

* pairing: ``random`` (each child an independent random pair of distinct
  strings among all five), ``shuffle`` (the five in a random order, each mated
  with the next), ``rest`` (only the four non-elite strings, shuffled, mated
  round the ring: "the remaining 4 strings"), ``double`` ("8 pairs": eight
  random pairs, the better four children kept), ``tournament`` (Krishnakumar's
  micro-GA: each parent the better of two random strings);
* convergence: ``cost`` (costs within 1% or unchanged) or ``edges``
  (Krishnakumar's test on the adjacency strings: at most 5% of the successor
  entries differ from the best string);
* crossover start: the first city of a parent (path strings), a random city,
  or city 0 (the first entry of an adjacency string);
* mates: distinct by index only, or distinct in content.

Every instance's optimum is certified by the MILP (:func:`subtask_opt.milp_optimum`)
on the paper's time model (``time_model="paper"``, planar_2r). Each reading runs
``--seeds`` seeds per instance, stopping at the certified optimum or after
``--max-generations``; a success is reaching the optimum within that budget, and
the generation is the first generation whose best string is optimal.

    python benchmarks/paper_micro_ga.py [--seeds 20] [--max-generations 20000]
        [--instances square20 random30/0] [--readings ...] [--json out.json]
    python benchmarks/paper_micro_ga.py --optima docs/figures/square20_optima.png

``--optima`` instead enumerates every optimal tour of square20 on the paper's
time model (:func:`subtask_opt.tour.exact.optimal_tours`), once with planar_2r's
limits and once with its rotation limits Kw and Kw_dot ten times larger (so
that only the distance matters), prints the counts and plots the optimum of the
first beside two optima of the second (the paper's Figs. 8 and 9).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from subtask_opt import SolverParams, builtin_case, milp_optimum, solve
from subtask_opt.arm.planar_problem import PlanarProblem
from subtask_opt.base.stop import MaxGenerations, TargetCost
from subtask_opt.ga.config import GAConfig
from subtask_opt.kinematics.planar import CartesianLimits, load_planar_arm
from subtask_opt.tour.exact import optimal_tours
from subtask_opt.tour.problem import MatrixProblem

# generation at which the paper reports the optimum (its Figs. 10 and 13)
PAPER_GENERATIONS = {"square20": 500, "random30": 800}
REL_TOL = 1e-9

_BASE = dict(population=5, elite=1, crossover_rate=1.0, mutation_rate=0.0,
             restart_on_convergence=True)
READINGS: dict[str, GAConfig] = {
    # the code before this study: random pairs among all five, cost test
    "random/cost": GAConfig(**_BASE, convergence_tol=0.01),
    "random/cost0": GAConfig(**_BASE, convergence_tol=0.0),
    "random/edges": GAConfig(**_BASE, convergence="edges", convergence_tol=0.05),
    "shuffle/cost": GAConfig(**_BASE, pairing="shuffle", convergence_tol=0.01),
    "shuffle/edges": GAConfig(**_BASE, pairing="shuffle", convergence="edges",
                              convergence_tol=0.05),
    "rest/cost": GAConfig(**_BASE, pairing="rest", convergence_tol=0.01),
    "rest/edges": GAConfig(**_BASE, pairing="rest", convergence="edges", convergence_tol=0.05),
    "double/cost": GAConfig(**_BASE, pairing="double", convergence_tol=0.01),
    "double/edges": GAConfig(**_BASE, pairing="double", convergence="edges",
                             convergence_tol=0.05),
    "tournament/cost": GAConfig(**_BASE, tournament=2, convergence_tol=0.01),
    "tournament/edges": GAConfig(**_BASE, tournament=2, convergence="edges",
                                 convergence_tol=0.05),
    "random/adjacency": GAConfig(**_BASE, convergence="adjacency", convergence_tol=0.05),
    "random/edges/start-random": GAConfig(**_BASE, convergence="edges", convergence_tol=0.05,
                                          crossover_start="random"),
    "random/edges/start-first": GAConfig(**_BASE, convergence="edges", convergence_tol=0.05,
                                         crossover_start="first"),
    "random/edges/distinct": GAConfig(**_BASE, convergence="edges", convergence_tol=0.05,
                                      distinct_mates=True),
    "random/cost/start-random": GAConfig(**_BASE, convergence_tol=0.01,
                                         crossover_start="random"),
    "random/edges0/start-random": GAConfig(**_BASE, convergence="edges", convergence_tol=0.0,
                                           crossover_start="random"),
    "random/edges/start-random/distinct": GAConfig(
        **_BASE, convergence="edges", convergence_tol=0.05, crossover_start="random",
        distinct_mates=True),
    "shuffle/edges/start-random": GAConfig(**_BASE, pairing="shuffle", convergence="edges",
                                           convergence_tol=0.05, crossover_start="random"),
    "double/edges/start-random": GAConfig(**_BASE, pairing="double", convergence="edges",
                                          convergence_tol=0.05, crossover_start="random"),
    "double/edges/start-random/distinct": GAConfig(
        **_BASE, pairing="double", convergence="edges", convergence_tol=0.05,
        crossover_start="random", distinct_mates=True),
    "tournament/edges/start-random": GAConfig(**_BASE, tournament=2, convergence="edges",
                                              convergence_tol=0.05, crossover_start="random"),
    "tournament/edges/start-random/distinct": GAConfig(
        **_BASE, tournament=2, convergence="edges", convergence_tol=0.05,
        crossover_start="random", distinct_mates=True),
    "double/edges/distinct": GAConfig(**_BASE, pairing="double", convergence="edges",
                                      convergence_tol=0.05, distinct_mates=True),
    "double/cost/start-random/distinct": GAConfig(
        **_BASE, pairing="double", convergence_tol=0.01, crossover_start="random",
        distinct_mates=True),
    "double/adjacency/start-random/distinct": GAConfig(
        **_BASE, pairing="double", convergence="adjacency", convergence_tol=0.05,
        crossover_start="random", distinct_mates=True),
}


def paper_instances(names: list[str], robot: str = "planar_2r") -> list[tuple[str, np.ndarray]]:
    """``(name, matrix)`` of each instance on the paper's time model; ``random30/g`` is
    random30 drawn with generator seed g; a ``+rot10`` suffix makes the rotation
    limits Kw and Kw_dot ten times larger (distance-dominated legs: square20 then
    has 14 optimal tours instead of one)."""
    arm = load_planar_arm(robot)
    c = arm.cartesian_limits
    free = load_planar_arm(robot, cartesian_limits=CartesianLimits(c.kv, c.ka, 10 * c.kw,
                                                            10 * c.kw_dot))
    out = []
    for name in names:
        base, plus, _ = name.partition("+rot10")
        family, _, gen = base.partition("/")
        sub = builtin_case(family, arm, seed=int(gen or 0))
        out.append((name, PlanarProblem(sub, free if plus else arm,
                                            time_model="paper").matrix))
    return out


def run_reading(matrix: np.ndarray, optimum: float, loop: GAConfig, seeds: int,
                max_generations: int) -> dict:
    """Success count and generations to the optimum of one reading on one matrix."""
    problem = MatrixProblem(matrix)
    params = SolverParams(preset="paper", paper_loop=loop)
    stop = [TargetCost(optimum, tolerance=REL_TOL), MaxGenerations(max_generations)]
    gens, restarts, times = [], [], []
    for seed in range(seeds):
        r = solve(problem, seed=seed, params=params, stop=stop)
        times.append(r.runtime_s)
        restarts.append(r.restarts / max(r.generations, 1))
        if r.total_time <= optimum * (1 + REL_TOL):
            gens.append(r.history.generation_of_best())
    return {"success": len(gens), "runs": seeds, "generations_to_optimum": gens,
            "restarts_per_generation": statistics.mean(restarts), "times_s": times}


def square20_optima(path: Path) -> dict:
    """Enumerate square20's optimal tours on the paper's model and plot three of them."""
    from subtask_opt.plotting.sequencing import save_optimal_tours_figure

    arm = load_planar_arm("planar_2r")
    c = arm.cartesian_limits
    free = load_planar_arm("planar_2r", cartesian_limits=CartesianLimits(c.kv, c.ka, 10 * c.kw,
                                                                  10 * c.kw_dot))
    sub = builtin_case("square20", arm)
    out = {}
    panels = []
    for label, robot in (("planar_2r limits", arm), ("rotation limits x10", free)):
        problem = PlanarProblem(sub, robot, time_model="paper")
        found = optimal_tours(problem.matrix)
        out[label] = {"optimum": found.cost, "count": len(found.tours),
                      "next_cost": found.next_cost}
        print(f"square20, paper model, {label}: {len(found.tours)} optimal tour(s) of "
              f"{found.cost:.4f} s; the best other tour {found.next_cost:.4f} s "
              f"(+{100 * (found.next_cost / found.cost - 1):.2f}%)")
        picks = [0] if len(panels) == 0 else [0, len(found.tours) - 1]
        for k in picks:
            panels.append((problem, found.tours[k],
                           f"{label}: optimum {k + 1} of {len(found.tours)}\n"
                           f"{found.cost:.4f} s"))
    save_optimal_tours_figure(panels, path, title=(
        "square20 on the paper's time model (eq. 6-19, k = 0.1): every optimum enumerated "
        "by MILP with no-good cuts"))
    print(f"wrote {path}")
    return out


def print_table(results: dict) -> None:
    """The readings x instances table of a run (``main``'s result or its JSON)."""
    readings = list(results["readings"])
    paper = {n: PAPER_GENERATIONS[n.partition("/")[0].partition("+")[0]]
             for n in results["instances"]}
    print(f"paper time model, planar_2r; {results['seeds']} seeds per reading, at most "
          f"{results['max_generations']} generations; success: reached the MILP-certified optimum; "
          "<=2x paper: reached it within twice the paper's generation ("
          + ", ".join(f"{n} ~{g}" for n, g in paper.items()) + ")")
    width = max(len(r) for r in readings)
    print(f"{'reading':<{width}}" + "".join(
        f" | {n + ': success, <=2x paper, median gen [IQR], restarts/gen':<60}"
        for n in results["instances"]))
    for reading in readings:
        row = f"{reading:<{width}}"
        for name in results["instances"]:
            r = results["instances"][name]["readings"][reading]
            gens = r["generations_to_optimum"]
            early = sum(g <= 2 * paper[name] for g in gens)
            if gens:
                q1, q2, q3 = np.percentile(gens, [25, 50, 75])
                med = f"{q2:.0f} [{q1:.0f}-{q3:.0f}]"
            else:
                med = "-"
            cell = (f"{r['success']:>3}/{r['runs']:<3} {early:>3}/{r['runs']:<3} {med:>20} "
                    f"{r['restarts_per_generation']:>6.3f}")
            row += f" | {cell:<60}"
        print(row)
    for name, inst in results["instances"].items():
        print(f"{name}: certified optimum {inst['optimum']:.4f} s")


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--max-generations", type=int, default=20_000)
    ap.add_argument("--instances", nargs="+", default=["square20", "random30/0"])
    ap.add_argument("--readings", nargs="+", default=list(READINGS), choices=list(READINGS))
    ap.add_argument("--json", type=Path)
    ap.add_argument("--optima", type=Path, help="enumerate and plot square20's optima instead")
    ap.add_argument("--table", type=Path, help="print the table of a --json file and exit")
    args = ap.parse_args(argv)
    if args.table:
        results = json.loads(args.table.read_text())
        print_table(results)
        return results
    if args.optima:
        return square20_optima(args.optima)

    results: dict = {"seeds": args.seeds, "max_generations": args.max_generations,
                     "instances": {}, "readings": {k: asdict(READINGS[k]) for k in args.readings}}
    for name, matrix in paper_instances(args.instances):
        optimum, _ = milp_optimum(matrix)
        results["instances"][name] = {"optimum": optimum, "readings": {}}
        solve(MatrixProblem(matrix), seed=0,  # compile before timing
              params=SolverParams(preset="paper"), stop=MaxGenerations(2))
        for reading in args.readings:
            t = time.perf_counter()
            r = run_reading(matrix, optimum, READINGS[reading], args.seeds, args.max_generations)
            r["wall_s"] = time.perf_counter() - t
            results["instances"][name]["readings"][reading] = r

    print_table(results)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(results, indent=1))
    return results


if __name__ == "__main__":
    main()
