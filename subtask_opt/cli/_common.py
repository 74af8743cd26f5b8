"""Argument types and output helpers shared by the CLI command modules."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np


def ascii_number(text: str) -> str:
    """``text`` if it is written in ASCII, else ``ValueError``: Python's ``int``/``float``
    read Arabic-Indic, full-width and other Unicode digits, which an option never means."""
    if not text.isascii():
        raise ValueError(f"not an ASCII number: {text!r}")
    return text


def point(text: str, dims: int = 2) -> tuple[float, ...]:
    """Parse ``"X,Y"`` (or ``"X,Y,H"`` for dims=3) into finite floats."""
    parts = text.split(",")
    if len(parts) != dims:
        raise argparse.ArgumentTypeError(
            f"expected {dims} comma-separated numbers, got {text!r}")
    try:
        values = tuple(float(ascii_number(p)) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number in {text!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"values must be finite, got {text!r}")
    return values


EXIT_OK = 0
"""The job succeeded."""
EXIT_FAILED = 1
"""The job ran and failed: no path, stall, collision, timeout, infeasible tour."""
EXIT_BAD_INPUT = 2
"""A user mistake: bad option, unreadable or malformed input (one line on stderr)."""
EXIT_INTERRUPTED = 130
"""Interrupted by SIGINT (Ctrl-C), as shells report it: one line, no partial output."""

MAX_GENERATIONS = 10_000_000
MAX_STALL = 1_000_000
MAX_RUNTIME_S = 86_400.0
MAX_WORKERS = 256
"""The most local worker processes ``--workers`` starts."""
MAX_INDEX = 10_000_000
"""The largest subtask index ``--first``/``--end`` take."""


def add_stop_options(parser: argparse.ArgumentParser, *, title: str, target: bool) -> Any:
    """The GA's stopping options, bounded (``--target`` too when ``target``); returns the
    argument group (a command may add its own)."""
    stop = parser.add_argument_group(title)
    stop.add_argument("--max-generations", type=int_in(1, MAX_GENERATIONS), metavar="N",
                      help=f"at most N generations, N in [1, {MAX_GENERATIONS}]")
    stop.add_argument("--time-limit", "--max-runtime", dest="max_runtime",
                      type=float_in(0.0, MAX_RUNTIME_S, open_low=True), metavar="SECONDS",
                      help=f"stop after this long, in (0, {MAX_RUNTIME_S:g}]")
    stop.add_argument("--no-improvement", type=int_in(1, MAX_STALL), metavar="N",
                      help=f"stop after N generations without a better tour, "
                           f"N in [1, {MAX_STALL}]")
    if target:
        stop.add_argument("--target", type=float_in(0.0, 1e12), metavar="SECONDS",
                          help="stop once the total time is at most this, in [0, 1e12]")
    return stop


def stop_criteria(args: argparse.Namespace) -> list[Any] | None:
    """The criteria :func:`add_stop_options` asked for (None: the solver's default)."""
    from subtask_opt.base.stop import MaxGenerations, MaxRuntime, NoImprovement, TargetCost

    criteria: list[Any] = []
    if args.max_generations is not None:
        criteria.append(MaxGenerations(args.max_generations))
    if args.max_runtime is not None:
        criteria.append(MaxRuntime(args.max_runtime))
    if args.no_improvement is not None:
        criteria.append(NoImprovement(args.no_improvement))
    if getattr(args, "target", None) is not None:
        criteria.append(TargetCost(args.target))
    return criteria or None


def failed(message: str) -> int:
    """Report a job that ran and failed (one line on stderr); return :data:`EXIT_FAILED`."""
    print(f"subtask-opt: failed: {' '.join(str(message).split())}", file=sys.stderr)
    return EXIT_FAILED


SEED_LIMIT = 2**63
PLOT_SUFFIXES = (".png", ".pdf", ".svg")
ANIMATION_SUFFIXES = (".gif",)


def seed(text: str) -> int:
    """A random seed: a whole number in [0, 2**63)."""
    try:
        value = int(ascii_number(text))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if not 0 <= value < SEED_LIMIT:
        raise argparse.ArgumentTypeError(f"a seed must be in [0, 2**63), got {text!r}")
    return value


def int_in(low: int, high: int) -> Any:
    """An argparse type: a whole number in [low, high]."""
    def parse(text: str) -> int:
        try:
            value = int(ascii_number(text))
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected a whole number >= {low} and <= {high}, "
                                             f"got {text!r}")
        return value
    parse.__name__ = "int"
    return parse


def float_in(low: float, high: float, *, open_low: bool = False) -> Any:
    """An argparse type: a finite number in [low, high] (or (low, high] with ``open_low``)."""
    def parse(text: str) -> float:
        try:
            value = float(ascii_number(text))
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        ok = math.isfinite(value) and (value > low if open_low else value >= low) \
            and value <= high
        if not ok:
            bracket = "(" if open_low else "["
            raise argparse.ArgumentTypeError(f"expected a number in {bracket}{low:g}, {high:g}], "
                                             f"got {text!r}")
        return value
    parse.__name__ = "float"
    return parse


def floats(text: str) -> tuple[float, ...]:
    """One or more comma-separated finite numbers > 0 (a scalar or one per joint)."""
    try:
        values = tuple(float(ascii_number(t)) for t in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers like 1.5 or 1.5,2, got {text!r}") \
            from None
    if not all(math.isfinite(v) and 0 < v < 1e9 for v in values):
        raise argparse.ArgumentTypeError(f"expected finite numbers in (0, 1e9), got {text!r}")
    return values


def _output(text: str, suffixes: tuple[str, ...] | None) -> str:
    from subtask_opt.base.errors import ParameterError
    from subtask_opt.base.files import check_output

    if not text.strip():
        raise argparse.ArgumentTypeError("the output path is empty")
    if suffixes and Path(text).suffix.lower() not in suffixes:
        raise argparse.ArgumentTypeError(
            f"{text!r} must end in {' or '.join(suffixes)}")
    try:
        check_output(text)
    except ParameterError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def json_output(text: str) -> str:
    """A path for ``--json`` (not empty, not a folder)."""
    return _output(text, None)


def plot_output(text: str) -> str:
    """A path for ``--plot`` (.png, .pdf or .svg)."""
    return _output(text, PLOT_SUFFIXES)


def animation_output(text: str) -> str:
    """A path for ``--animate`` (.gif)."""
    return _output(text, ANIMATION_SUFFIXES)


def output_folder(text: str) -> str:
    """A folder for many outputs (``reproduce --out``): not a file, and writable (a missing
    one is created)."""
    from subtask_opt.base.errors import ParameterError
    from subtask_opt.base.files import check_output

    if not text.strip() or text.strip() == "-":
        raise argparse.ArgumentTypeError(f"expected a folder, got {text!r}")
    if Path(text).exists() and not Path(text).is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a file, not a folder")
    try:
        check_output(Path(text) / "probe", "output folder")
    except ParameterError as exc:
        raise argparse.ArgumentTypeError(str(exc).replace("/probe", "")) from None
    return text


def html_output(text: str) -> str:
    """A path for an HTML page (``--view``)."""
    return _output(text, (".html",))


def add_outputs(parser: argparse.ArgumentParser, *, what: str = "the result",
                plot: str | None = "a figure of the result") -> None:
    """``--json OUT`` and (unless ``plot`` is None) ``--plot OUT.png``."""
    parser.add_argument("--json", metavar="OUT.json", type=json_output,
                        help=f"write {what} as JSON")
    if plot is not None:
        parser.add_argument("--plot", metavar="OUT.png", type=plot_output,
                            help=f"write {plot} (.png, .pdf or .svg)")


def add_no_progress(parser: argparse.ArgumentParser) -> None:
    """The one progress switch: bars are drawn only on a terminal, and never with it."""
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress bar (bars appear only on a terminal anyway)")


def refuse_overwriting_inputs(inputs: list[str | Path | None],
                              outputs: list[str | Path | None]) -> None:
    """Raise :class:`ParameterError` when an output path is one of the input files (the
    same file by another name too: a symbolic or hard link), or two outputs are one file."""
    import os

    from subtask_opt.base.errors import ParameterError

    def identity(path: str | Path) -> tuple[int, int] | Path:
        try:
            info = os.stat(path)
            return (info.st_dev, info.st_ino)
        except (OSError, ValueError):
            return Path(path).resolve()

    existing = {identity(i): i for i in inputs if i and Path(i).is_file()}
    seen: dict[tuple[int, int] | Path, str | Path] = {}
    for out in outputs:
        if not out:
            continue
        key = identity(out)
        if key in existing:
            raise ParameterError(f"output {str(out)!r} is also an input file "
                                 f"({str(existing[key])!r}); choose another path")
        if key in seen or Path(out).resolve() in {Path(s).resolve() for s in seen.values()}:
            raise ParameterError(f"outputs {str(seen.get(key, out))!r} and {str(out)!r} are "
                                 "the same file; choose another path")
        seen[key] = out


def point3(text: str) -> tuple[float, ...]:
    return point(text, 3)


def _whole_number(text: str, minimum: int) -> int:
    try:
        value = int(ascii_number(text))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"expected a whole number >= {minimum}, got {text!r}")
    return value


def positive_int(text: str) -> int:
    return _whole_number(text, 1)


def non_negative_int(text: str) -> int:
    return _whole_number(text, 0)


def ascii_float(text: str) -> float:
    """An argparse type: any number written in ASCII (its range is left to the parameter
    class the option fills, which names the field)."""
    try:
        return float(ascii_number(text))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def positive_float(text: str) -> float:
    try:
        value = float(ascii_number(text))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.floating,)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    return value


def write_json(path: str | Path, payload: dict[str, Any]) -> None:
    """Write ``payload`` as JSON (numpy values converted, inf/nan as null) to a temporary
    file renamed onto ``path``: a failed write leaves no partial file."""
    from subtask_opt.base.files import write_text_atomic

    write_text_atomic(path, json.dumps(_jsonable(payload), indent=2) + "\n", "--json file")


def output_file(path: str | Path) -> Any:
    """``with output_file(path) as tmp:`` write to ``tmp``; renamed onto ``path`` when the
    block succeeds, removed when it fails (:func:`subtask_opt.base.files.atomic_output`)."""
    from subtask_opt.base.files import atomic_output

    return atomic_output(path)


def ensure_parent(path: str | Path) -> Path:
    """Create the folder of an output file if needed and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def scheduler_address(text: str) -> str:
    """``--scheduler``: a dask address ``PROTOCOL://HOST[:PORT]`` in printable ASCII."""
    protocol, _, rest = text.partition("://")
    if not (text.isascii() and text.isprintable() and protocol.isalpha() and rest.strip()):
        raise argparse.ArgumentTypeError(f"expected a scheduler address like "
                                         f"tcp://head:8786, got {text!r}")
    return text


def add_workers(parser: argparse.ArgumentParser, *, what: str = "the jobs",
                serial_default: bool = False) -> None:
    """``--scheduler ADDRESS | --workers N``: where :func:`workers_options` runs ``what``.

    The same group on ``batch``, ``bench reactive``, ``bench agv`` and the
    benchmark scripts: no option runs on local workers, one per core (a Dask
    LocalCluster, or a process pool without dask); ``--workers 0`` runs here.
    ``serial_default``: no option runs here (benchmarks whose per-solve times
    would change if solves shared the cores).
    """
    where = parser.add_argument_group(
        "where to run", f"{what} run on local worker processes (a Dask cluster, or a "
                        "process pool without dask) or on an existing Dask cluster")
    group = where.add_mutually_exclusive_group()
    group.add_argument("--scheduler", metavar="ADDRESS", type=scheduler_address,
                       help="address of a running dask scheduler, e.g. tcp://head:8786 "
                            "(needs pip install subtask_opt[cluster])")
    default = "0" if serial_default else "the machine's cores"
    group.add_argument("--workers", type=int_in(0, MAX_WORKERS), metavar="N",
                       default=0 if serial_default else None,
                       help=f"local worker processes, N in [0, {MAX_WORKERS}] (default: "
                            f"{default}; 0 runs in this process)")


def workers_options(args: argparse.Namespace) -> dict[str, Any]:
    """``{"workers": ..., "scheduler": ...}`` of :func:`add_workers` (the default resolved)."""
    from subtask_opt.batch.pool import default_workers

    if args.scheduler is not None:
        return {"workers": None, "scheduler": args.scheduler}
    return {"workers": default_workers() if args.workers is None else args.workers,
            "scheduler": None}


def where_text(options: dict[str, Any]) -> str:
    """Where :func:`workers_options` runs, in words (``"2 local workers"``)."""
    if options["scheduler"] is not None:
        return str(options["scheduler"])
    n = options["workers"]
    return "this process" if n == 0 else f"{n} local worker{'s' * (n != 1)}"
