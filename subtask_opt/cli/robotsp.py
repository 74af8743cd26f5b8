"""``subtask-opt bench robotsp``: RoboTSP's drilling benchmark (see
:mod:`subtask_opt.papers.robotsp`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from subtask_opt.cli._common import EXIT_OK, add_outputs, seed, write_json

DEFAULT_DATA = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "robotsp"


def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``bench robotsp`` (``plan`` is unused: no planner here)."""
    b = bench.add_parser(
        "robotsp", help="RoboTSP's 245-hole drilling benchmark on vs060_drill",
        description="Ours beside RoboTSP's method, TSP C-space and LKH's GTSP (from "
                    "subtask_opt.tour.peers) on RoboTSP's subsets: executed (validated ruckig) "
                    "time, CPU split, configurations per hole; RoboTSP's published figures "
                    "as context (the robot frames were reconstructed).")
    b.add_argument("--data", default=str(DEFAULT_DATA), metavar="DIR",
                   help="folder with targets.csv, subsets.json, obstacles.json, published.json")
    b.add_argument("--sizes", default=None, metavar="25,50,...",
                   help="subset sizes to run (default all)")
    b.add_argument("--seed", type=seed, default=0, help="solver seed (default 0)")
    add_outputs(b, plot=None)
    b.set_defaults(handler=_run)


def _sizes(text: str | None) -> list[int] | None:
    from subtask_opt.base.errors import ParameterError

    if text is None:
        return None
    try:
        return [int(s) for s in text.split(",")]
    except ValueError:
        raise ParameterError(f"--sizes must be comma-separated whole numbers, got "
                             f"{text!r}") from None


def _run(args: argparse.Namespace) -> int:
    from subtask_opt.papers.robotsp import run, table

    report = run(args.data, sizes=_sizes(args.sizes), seed=args.seed)
    print(table(report))
    if args.json:
        write_json(args.json, report)
        print(f"wrote {args.json}")
    return EXIT_OK
