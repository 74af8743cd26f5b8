"""``subtask-opt batch``: solve many subtask files at once, locally or on a Dask cluster."""

from __future__ import annotations

import argparse
import sys
import time

from subtask_opt.cli._common import (
    EXIT_FAILED,
    EXIT_OK,
    add_no_progress,
    add_stop_options,
    add_workers,
    float_in,
    json_output,
    output_file,
    plot_output,
    refuse_overwriting_inputs,
    seed,
    stop_criteria,
    where_text,
    workers_options,
    write_json,
)

MAX_JOB_TIME_S = 86_400.0
"""The longest ``--job-time-limit``."""
FILE_OPTIONS = ("robot", "time_model", "home", "scene", "standoff", "axis_step", "tool_frame",
                "detours")
"""The options that become :class:`~subtask_opt.batch.Job` fields of every file job."""

# failed jobs printed one per line before "... and N more"
_SHOWN_FAILURES = 20


def register(root: argparse._SubParsersAction) -> None:
    """Add the ``batch`` command."""
    from subtask_opt.arm.timing import TIME_MODELS
    from subtask_opt.cli.solve import add_cell_options, signed_numbers

    p = root.add_parser(
        "batch",
        help="solve many subtask files in parallel (local processes or a Dask cluster)",
        description="Solve every job of JOBS (subtask files, or JSON manifests of jobs with "
                    "robot, time model and seed each) on local worker processes or an existing "
                    "dask.distributed cluster, and write one result per job as JSON. A job that "
                    "fails is reported with its error; the others run on.",
    )
    p.add_argument("jobs", nargs="+", metavar="JOBS",
                   help='subtask files (.csv with header x,y[,theta] or .json) or manifests '
                        '(.json: [{"id": ..., "case": FILE|square20|random30, "robot": ..., '
                        '"time_model": ..., "seed": ..., "case_seed": ...}, ...])')
    files = p.add_argument_group(
        "the jobs of subtask and target files (a manifest gives each job its own; the cell "
        "options are for serial arms)")
    files.add_argument("--robot", metavar="NAME|PATH.urdf",
                       help="robot of every file job (default planar_2r); a serial arm "
                            "(ur5, ...) takes target files x,y,z,dx,dy,dz or poses")
    files.add_argument("--time-model", choices=TIME_MODELS, metavar="MODEL",
                       help="time model of every planar file job (default joint)")
    files.add_argument("--home", type=signed_numbers, metavar="X,Y|Q1,...,QN",
                       help="a planar arm's home point X,Y (m), or a serial arm's home "
                            "configuration in degrees (default: the robot file's)")
    add_cell_options(files)
    files.add_argument("--no-detours", dest="detours", action="store_false", default=None,
                       help="(serial arms) forbid legs whose straight joint motion collides "
                            "instead of planning them around the obstacles")
    add_workers(p, what="the jobs")
    p.add_argument("--seed", type=seed, default=None, metavar="N",
                   help="solver seed of every job (default: each manifest job's own seed, "
                        "0 for subtask files)")
    stop = add_stop_options(p, title="stopping, per job (any criterion given stops the run)",
                            target=False)
    stop.add_argument("--job-time-limit", type=float_in(0.0, MAX_JOB_TIME_S, open_low=True),
                      default=None, metavar="SECONDS",
                      help=f"stop a job that runs longer than this, in (0, "
                           f"{MAX_JOB_TIME_S:g}] (its reading and building too, unlike "
                           "--time-limit): it fails alone, the others keep their answers")
    p.add_argument("--json", required=True, metavar="OUT.json", type=json_output,
                   help="write every job's result (and the failed jobs' errors) as JSON")
    p.add_argument("--plot", metavar="OUT.png", type=plot_output,
                   help="write a figure of every job's total time, failed jobs marked")
    add_no_progress(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from subtask_opt.batch import load_jobs, solve_many

    refuse_overwriting_inputs([*args.jobs, args.scene], [args.json, args.plot])
    options = {name: getattr(args, name) for name in FILE_OPTIONS
               if getattr(args, name) is not None}
    jobs = load_jobs(args.jobs, **options)
    where = workers_options(args)
    started = time.perf_counter()
    results = solve_many(jobs, seeds=args.seed, stop=stop_criteria(args),
                         client=where["scheduler"], workers=where["workers"],
                         progress=not args.no_progress and sys.stderr.isatty(),
                         job_time_limit=args.job_time_limit)
    wall = time.perf_counter() - started
    failed = [r for r in results if not r.success]
    # wall_s includes starting the workers and loading their kernels;
    # benchmarks/batch.py measures the per-job overhead after warm-up
    slots = len({r.worker for r in results if r.worker})
    summary = {
        "jobs": len(results), "succeeded": len(results) - len(failed), "failed": len(failed),
        "wall_s": wall,
        "where": where_text(where),
        "workers_used": slots, "jobs_time_s": sum(r.worker_time_s for r in results),
    }
    write_json(args.json, {"summary": summary, "jobs": [r.to_dict() for r in results]})
    print(f"{len(results)} jobs: {summary['succeeded']} solved, {len(failed)} failed "
          f"({wall:.2f} s on {summary['where']})")
    for r in failed[:_SHOWN_FAILURES]:
        print(f"  failed {r.id}: {r.error}")
    if len(failed) > _SHOWN_FAILURES:
        print(f"  ... and {len(failed) - _SHOWN_FAILURES} more (see {args.json})")
    print(f"wrote {args.json}")
    if args.plot:
        from subtask_opt.plotting.batch import save_batch_figure

        with output_file(args.plot) as tmp:
            save_batch_figure(results, tmp, title=f"batch of {len(results)} jobs on "
                                                  f"{summary['where']}")
        print(f"wrote {args.plot}")
    return EXIT_FAILED if failed else EXIT_OK
