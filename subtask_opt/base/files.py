"""Reading user files safely: a size limit before reading, a nesting limit before parsing JSON.

Every reader of the package goes through :func:`read_text` (and :func:`parse_json` for
JSON), so a 50 MB one-line CSV, a file nested thousands deep or a number with thousands
of digits is refused with one :class:`~subtask_opt.base.errors.InputDataError` line
naming the file and the limit, never a ``RecursionError`` or ``OverflowError``.
"""

from __future__ import annotations

import json
import math
import os
import re
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError

MAX_FILE_BYTES = 64 * 1024 * 1024
"""The largest input file any reader accepts (64 MiB)."""
MAX_JSON_DEPTH = 32
"""The deepest JSON nesting any reader accepts."""
MAX_NUMBER_CHARS = 64
"""The longest number literal a JSON input may hold (a float needs at most ~25)."""


def read_text(path: str | Path, what: str, *, max_bytes: int = MAX_FILE_BYTES) -> str:
    """The text of ``path`` (UTF-8, a leading BOM dropped), refusing files over ``max_bytes``."""
    path = Path(path)
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        raise InputDataError(f"{what} not found: {path}") from None
    except OSError as exc:
        raise InputDataError(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    if path.is_dir():
        raise InputDataError(f"{what} {path} is a folder, not a file")
    if size > max_bytes:
        raise InputDataError(f"{what} {path} has {size} bytes; the limit is {max_bytes}")
    try:
        return path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputDataError(f"{what} {path} is not UTF-8 text ({exc.reason} at byte "
                             f"{exc.start})") from None
    except OSError as exc:
        raise InputDataError(f"cannot read {what} {path}: {exc.strerror or exc}") from None


_JSON_STRING = re.compile(r'"(?:[^"\\]|\\.)*"')


def json_depth(text: str) -> int:
    """The deepest ``[``/``{`` nesting of a JSON text (brackets inside strings ignored).

    Runs on the raw text before parsing (vectorised), so a deeply nested file
    cannot exhaust the parser's recursion.
    """
    stripped = _JSON_STRING.sub('""', text).encode("utf-8", "replace")
    codes = np.frombuffer(stripped, dtype=np.uint8)
    step = ((codes == ord("[")) | (codes == ord("{"))).astype(np.int64) - (
        (codes == ord("]")) | (codes == ord("}")))
    return int(max(np.max(np.cumsum(step), initial=0), 0))


def _finite_float(text: str) -> float:
    if len(text) > MAX_NUMBER_CHARS:
        raise ValueError(f"a number of {len(text)} characters (limit {MAX_NUMBER_CHARS})")
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"the number {text[:20]} is out of range")
    return value


def _reject_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a finite number")


def parse_json(text: str, where: str, *, max_depth: int = MAX_JSON_DEPTH) -> Any:
    """Parse JSON whose nesting is at most ``max_depth``; numbers become finite floats or ints
    of at most :data:`MAX_NUMBER_CHARS` digits; NaN and Infinity are refused."""
    depth = json_depth(text)
    if depth > max_depth:
        raise InputDataError(f"{where}: brackets nested {depth} deep, deeper than the "
                             f"limit of {max_depth}")
    try:
        return json.loads(text, parse_float=_finite_float, parse_int=_checked_int,
                          parse_constant=_reject_constant)
    except json.JSONDecodeError as exc:
        raise InputDataError(f"{where}, line {exc.lineno}: not valid JSON ({exc.msg})") from None
    except (ValueError, RecursionError) as exc:
        raise InputDataError(f"{where}: {exc}") from None


def _checked_int(text: str) -> int:
    if len(text) > MAX_NUMBER_CHARS:
        raise ValueError(f"a number of {len(text)} digits (limit {MAX_NUMBER_CHARS})")
    return int(text)


@contextmanager
def quiet_stderr() -> Iterator[None]:
    """Silence what C++ libraries write to stderr (their own error lines)."""
    with _quiet(sys.stderr, 2):
        yield


@contextmanager
def quiet_stdout() -> Iterator[None]:
    """Silence what C++ libraries write to stdout (solver banners)."""
    with _quiet(sys.stdout, 1):
        yield


@contextmanager
def _quiet(stream: Any, fd: int) -> Iterator[None]:
    """Point the process's file descriptor ``fd`` (where C++ code writes, whatever
    ``sys.stderr``/``sys.stdout`` have been replaced by) at /dev/null for the block."""
    try:
        if stream is not None:
            stream.flush()
        saved = os.dup(fd)
    except (AttributeError, OSError, ValueError):  # no such descriptor: nothing to silence
        yield
        return
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), fd)
            yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)
