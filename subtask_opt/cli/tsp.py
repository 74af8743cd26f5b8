"""``subtask-opt tsp FILE.tsp``: solve a TSPLIB instance and prove how good the tour is."""

from __future__ import annotations

import argparse

from subtask_opt.cli._common import (
    EXIT_OK,
    MAX_RUNTIME_S,
    add_no_progress,
    add_outputs,
    float_in,
    output_file,
    refuse_overwriting_inputs,
    seed,
    write_json,
)

DEFAULT_TIME_LIMIT = 10.0


def register(root: argparse._SubParsersAction) -> None:
    """Add the ``tsp`` command."""
    p = root.add_parser(
        "tsp", help="solve a TSPLIB .tsp file and bound the gap to the optimum",
        description="Read a TSPLIB file (EUC_2D, CEIL_2D, ATT, GEO or EXPLICIT weights), find "
                    "a short closed tour with the micro-GA solver, and prove a Held-Karp "
                    "lower bound: the tour is at most 'gap' above the optimum. Lengths are in "
                    "TSPLIB units (integer distances under the file's rounding rule).")
    p.add_argument("file", metavar="FILE.tsp", help="the TSPLIB file")
    p.add_argument("--time-limit", type=float_in(0.0, MAX_RUNTIME_S, open_low=True),
                   default=DEFAULT_TIME_LIMIT, metavar="SECONDS",
                   help=f"stop the search after this long, in (0, {MAX_RUNTIME_S:g}] (default "
                        f"{DEFAULT_TIME_LIMIT:g}); it "
                        "also stops once the tour stops improving. The lower bound then gets "
                        "what the search left, and at least a quarter of the limit")
    p.add_argument("--seed", type=seed, default=0, help="solver seed (default 0)")
    add_outputs(p, what="order, length, lower_bound, gap_bound and runtime_s",
                plot="the tour over the node coordinates")
    add_no_progress(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from subtask_opt.base.errors import InputDataError
    from subtask_opt.tour.tsplib import read_tsplib, solve_tsp

    refuse_overwriting_inputs([args.file], [args.json, args.plot])
    instance = read_tsplib(args.file)
    if args.plot and instance.coordinates is None:
        raise InputDataError(f"{args.file}: --plot needs node coordinates, and this "
                             f"{instance.edge_weight_type} file has none")
    solution = solve_tsp(instance, time_limit=args.time_limit, seed=args.seed,
                         progress=not args.no_progress)
    print(f"{instance.name}: {instance.dimension} cities, {instance.edge_weight_type}")
    print(f"tour length  {solution.length}")
    print(f"lower bound  {solution.lower_bound:g}")
    print(f"gap          <= {100 * solution.gap_bound:.3f}% above the optimum")
    print(f"runtime      {solution.runtime_s:.2f} s (bound {solution.bound_runtime_s:.2f} s, "
          f"{solution.generations} generations, seed {solution.seed})")
    if args.json:
        payload = solution.to_dict()
        # the shape fields of every solver JSON (TSPLIB tours are closed and unconstrained;
        # "tour" already holds the 1-based TSPLIB tour here, so the shape is "tour_shape")
        payload.update({"total_time": solution.length, "tour_shape": "closed",
                        "start": int(solution.order[0]), "end": None, "home": None,
                        "precedence": 0})
        write_json(args.json, payload)
        print(f"wrote {args.json}")
    if args.plot:
        from subtask_opt.plotting.tsp import save_tour_figure

        with output_file(args.plot) as tmp:
            save_tour_figure(instance, solution, tmp)
        print(f"wrote {args.plot}")
    return EXIT_OK
