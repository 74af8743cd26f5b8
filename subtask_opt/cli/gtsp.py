"""``subtask-opt gtsp FILE``: solve a GTSPLIB (or PCGLNS) instance and bound the gap."""

from __future__ import annotations

import argparse

from subtask_opt.cli._common import (
    EXIT_OK,
    add_no_progress,
    add_outputs,
    int_in,
    positive_float,
    refuse_overwriting_inputs,
    seed,
    write_json,
)

DEFAULT_TIME_LIMIT = 10.0


def register(root: argparse._SubParsersAction) -> None:
    """Add the ``gtsp`` command."""
    p = root.add_parser(
        "gtsp", help="solve a GTSPLIB .gtsp (or PCGLNS) file: one vertex of every set",
        description="Read a GTSPLIB file (TYPE GTSP or AGTSP; EUC_2D, CEIL_2D, GEO, ATT or "
                    "EXPLICIT weights; GTSP_SET_SECTION) or a PCGLNS file (precedence between "
                    "sets, a start set, -1 for a forbidden arc), find a cheap closed tour "
                    "through one vertex of every set with the clustered micro-GA, and prove a "
                    "lower bound: the tour is at most 'gap' above the optimum. Costs are "
                    "recomputed from the file's weights.")
    p.add_argument("file", metavar="FILE", help="the GTSPLIB or PCGLNS file")
    p.add_argument("--time-limit", type=positive_float, default=DEFAULT_TIME_LIMIT,
                   metavar="SECONDS",
                   help=f"stop the search after this long (default {DEFAULT_TIME_LIMIT:g}); it "
                        "also stops once the tour stops improving. The lower bound then gets "
                        "what the search left, and at least a quarter of the limit")
    p.add_argument("--seed", type=seed, default=0, help="solver seed (default 0)")
    p.add_argument("--runs", type=int_in(1, 1000), default=None, metavar="N",
                   help="independent micro-GA runs, the best kept (default: the solver's)")
    p.add_argument("--certify", action="store_true",
                   help="prove the tour optimal (or not) by branch and cut (arc MILP when "
                        "asymmetric), in up to max(--time-limit, 60) more seconds")
    add_outputs(p, what="tour (the file's vertex ids, one per set), cost, lower_bound, gap "
                        "and runtime_s",
                plot="the tour over the vertex coordinates")
    add_no_progress(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from subtask_opt.base.errors import InputDataError
    from subtask_opt.tour.gtsplib import read_gtsplib, solve_gtsp

    refuse_overwriting_inputs([args.file], [args.json, args.plot])
    instance = read_gtsplib(args.file)
    if args.plot and instance.coordinates is None:
        raise InputDataError(f"{args.file}: --plot needs vertex coordinates, and this "
                             f"{instance.edge_weight_type} file has none")
    solution = solve_gtsp(instance, time_limit=args.time_limit, seed=args.seed, runs=args.runs,
                          certify=args.certify, progress=not args.no_progress)
    print(f"{instance.name}: {instance.problem_type}, {instance.dimension} vertices in "
          f"{instance.set_count} sets, {instance.edge_weight_type}"
          + (f", {len(instance.precedence)} precedence pairs" if instance.precedence else ""))
    print(f"cost         {solution.cost:g}")
    print(f"lower bound  {solution.lower_bound:g}")
    print(f"gap          <= {100 * solution.gap:.3f}% above the optimum")
    if solution.certified is not None:
        print(f"certificate  {solution.certified}")
    print(f"runtime      {solution.runtime_s:.2f} s (search {solution.search_runtime_s:.2f} s, "
          f"bound {solution.bound_runtime_s:.2f} s, {solution.generations} generations in "
          f"{solution.runs} runs, seed {solution.seed})")
    if args.json:
        write_json(args.json, solution.to_dict())
        print(f"wrote {args.json}")
    if args.plot:
        from subtask_opt.plotting.gtsp import save_gtsp_figure

        save_gtsp_figure(instance, solution, args.plot)
        print(f"wrote {args.plot}")
    return EXIT_OK
