"""``subtask-opt reproduce PAPER``: a source paper's experiments, ours beside its numbers."""

from __future__ import annotations

import argparse
import sys

from subtask_opt.cli._common import (
    EXIT_OK,
    add_no_progress,
    add_workers,
    output_folder,
    seed,
    workers_options,
)

PAPER_IDS = ("000", "001", "002", "003", "004")


def register(root: argparse._SubParsersAction) -> None:
    """Add the ``reproduce`` command."""
    p = root.add_parser(
        "reproduce", help="reproduce a source paper: its figures, and its numbers beside ours",
        description="Run paper PAPER's experiments with the paper's parameters (000 thesis grid "
                    "planners, 001 fuzzy navigation, 002 sequencing micro-GA, 003 MAKLINK/PSO, "
                    "004 AGV), write its figures and tables into --out, and print every "
                    "numbered result of the paper beside ours with the deviation.")
    p.add_argument("paper", metavar="PAPER",
                   help=f"the paper's number: {', '.join(PAPER_IDS)}")
    p.add_argument("--out", default="out/papers", metavar="DIR", type=output_folder,
                   help="folder for the figures and tables (default: out/papers)")
    p.add_argument("--quick", action="store_true",
                   help="fewer seeds and runs (a smoke test; the numbers are less settled)")
    p.add_argument("--seed", type=seed, default=0, help="first seed of the stochastic runs")
    add_workers(p, what="paper 004's suite runs", serial_default=True)
    add_no_progress(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from subtask_opt.base.errors import ParameterError
    from subtask_opt.papers import PAPERS, reproduce

    if args.paper not in PAPERS:
        raise ParameterError(f"PAPER must be one of {', '.join(PAPERS)}, got {args.paper!r}")
    if args.paper != "004" and (args.scheduler is not None or args.workers):
        given = "--scheduler" if args.scheduler is not None else "--workers"
        raise ParameterError(f"{given} applies to paper 004's suite only; paper {args.paper} "
                             "runs in this process")
    where = workers_options(args)
    map_runs = None
    if where["scheduler"] is not None or where["workers"]:
        from subtask_opt.batch import suite_mapper, warm_agv

        map_runs = suite_mapper(**where, warm_up=warm_agv, desc="agv suite",
                                progress=not args.no_progress and sys.stderr.isatty())
    report = reproduce(args.paper, Path(args.out), quick=args.quick, seed=args.seed,
                       map_runs=map_runs)
    print(f"paper {report.paper}: {report.title}"
          f"{' (quick)' if report.quick else ''} - {report.seconds:.1f} s")
    print(report.table())
    print(f"wrote {len(report.files)} figures and table_{report.paper}.txt/.md/.json "
          f"into {args.out}")
    return EXIT_OK
