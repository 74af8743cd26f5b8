"""Command-line interface: ``subtask-opt solve | plan ... | bench ...``.

Each command family lives in :mod:`subtask_opt.commands` and registers its
argparse sub-parsers; heavy imports (numba, Pinocchio) happen only inside the
handlers, so ``--help`` is instant. A user mistake prints one line and exits 2.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import sys
from collections.abc import Sequence
from typing import Any

from subtask_opt.base.errors import NoPathError, SubtaskOptError, TimeLimitReached
from subtask_opt.cli._common import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK

EPILOG = ("exit codes: 0 the job succeeded; 1 it ran and failed (no path, stall, collision, "
          "infeasible); 2 bad input (one line on stderr); 130 interrupted (Ctrl-C)")


class _Parser(argparse.ArgumentParser):
    """argparse that reports a usage mistake as one line and exit code 2, and
    reads ``--start -50,-50`` as a value, not as an option."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("epilog", EPILOG)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-\.?\d[\d.,eE+-]*$")

    def _get_values(self, action: argparse.Action, arg_strings: list[str]) -> Any:
        # argparse drops a lone "--" given as an option's value and hands the handler an
        # empty list; it is a missing value
        if action.option_strings and action.nargs is None and arg_strings == ["--"]:
            self.error(f"argument {'/'.join(action.option_strings)}: expected a value, got '--'")
        return super()._get_values(action, arg_strings)

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    from subtask_opt.cli import (
        agv,
        batch,
        grid,
        gtsp,
        polygon,
        reactive,
        reproduce,
        robotsp,
        solve,
        tsp,
    )

    parser = _Parser(
        prog="subtask-opt",
        description="Minimum-time subtask sequencing for robot arms, and mobile-robot planners.",
    )
    root = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    root.required = True
    plan = root.add_parser("plan", help="plan a mobile-robot path").add_subparsers(
        dest="world", metavar="WORLD", parser_class=_Parser)
    plan.required = True
    bench = root.add_parser("bench", help="run a benchmark and print its table").add_subparsers(
        dest="suite", metavar="SUITE", parser_class=_Parser)
    bench.required = True
    solve.register(root)
    tsp.register(root)
    gtsp.register(root)
    batch.register(root)
    reproduce.register(root)
    for family in (grid, polygon, reactive, agv, robotsp):
        family.register(plan, bench)
    return parser


def _discard_stdout() -> None:
    """Point stdout at the null device, so that the interpreter's last flush of a closed
    pipe does not fail once more on exit."""
    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError):  # no file descriptor (a captured stdout)
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return the process exit code (see :data:`EPILOG`)."""
    for stream in (sys.stdout, sys.stderr):
        # a name from an input file that no terminal encoding can show is escaped, not fatal
        with contextlib.suppress(AttributeError, ValueError):
            stream.reconfigure(errors="backslashreplace")  # type: ignore[union-attr]
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help (0) or a usage mistake (2, already printed)
        return int(exc.code or 0)
    try:
        return int(args.handler(args) or EXIT_OK)
    except (NoPathError, TimeLimitReached) as exc:  # the job ran, and found no answer
        print(f"subtask-opt: failed: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except SubtaskOptError as exc:
        print(f"subtask-opt: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BrokenPipeError:  # whoever read stdout left early (`| head`): not bad input
        _discard_stdout()
        print("subtask-opt: failed: standard output was closed before the run finished",
              file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt:  # Ctrl-C: outputs are written whole or not at all
        print("subtask-opt: interrupted; no output was written for the unfinished work",
              file=sys.stderr)
        return EXIT_INTERRUPTED
    except MemoryError:
        print("subtask-opt: failed: out of memory (a smaller problem, or fewer workers, "
              "needs less)", file=sys.stderr)
        return EXIT_FAILED
    except OSError as exc:  # unreadable input, unwritable output
        name = getattr(exc, "filename", None)
        what = f"{exc.strerror or exc}: {name}" if name else str(exc)
        print(f"subtask-opt: error: {what}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
