"""Reading user files safely: a size limit before reading, a nesting limit before parsing JSON.

Every reader of the package goes through :func:`read_text` (and :func:`parse_json` for
JSON), so a 50 MB one-line CSV, a file nested thousands deep or a number with thousands
of digits is refused with one :class:`~subtask_opt.base.errors.InputDataError` line
naming the file and the limit, never a ``RecursionError`` or ``OverflowError``.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import stat
import sys
import tempfile
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
MIN_FREE_BYTES = 64 * 1024
"""An output folder with less free space than this is refused before any work starts."""
"""The longest number literal a JSON input may hold (a float needs at most ~25)."""


def _refuse_special(path: Path, what: str, mode: int) -> None:
    """Raise unless ``mode`` (of ``os.stat``) is a regular file's."""
    if stat.S_ISDIR(mode):
        raise InputDataError(f"{what} {path} is a folder, not a file")
    if not stat.S_ISREG(mode):
        kind = ("a pipe (FIFO)" if stat.S_ISFIFO(mode) else "a device" if
                stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else "a socket" if
                stat.S_ISSOCK(mode) else "not a regular file")
        raise InputDataError(f"{what} {path} is {kind}; give a regular file")


def check_input_file(path: str | Path, what: str, *, max_bytes: int = MAX_FILE_BYTES) -> Path:
    """``path`` if it names a regular file of at most ``max_bytes`` (for files that a C++
    parser opens itself, such as a URDF): never a FIFO, a device or a folder."""
    path = Path(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise InputDataError(f"{what} not found: {path}") from None
    except (OSError, ValueError) as exc:
        raise InputDataError(f"cannot read {what} {path}: "
                             f"{getattr(exc, 'strerror', None) or exc}") from None
    _refuse_special(path, what, info.st_mode)
    if info.st_size > max_bytes:
        raise InputDataError(f"{what} {path} has {info.st_size} bytes; the limit is {max_bytes}")
    return path


def read_bytes(path: str | Path, what: str, *, max_bytes: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of the regular file ``path``, at most ``max_bytes`` of them.

    A FIFO, a device (``/dev/zero``, ``/dev/urandom``), a socket or a folder is refused
    before it is opened, and the read itself stops after ``max_bytes + 1`` bytes, so a
    file that grows while it is read cannot exhaust memory either.
    """
    path = check_input_file(path, what, max_bytes=max_bytes)
    try:
        # O_NONBLOCK: a path swapped for a FIFO after the check cannot block the open
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as fh:
            _refuse_special(path, what, os.fstat(fh.fileno()).st_mode)
            data = fh.read(max_bytes + 1)
    except OSError as exc:
        raise InputDataError(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    if len(data) > max_bytes:
        raise InputDataError(f"{what} {path} has more than {max_bytes} bytes; the limit is "
                             f"{max_bytes}")
    return data


def read_text(path: str | Path, what: str, *, max_bytes: int = MAX_FILE_BYTES) -> str:
    """The text of the regular file ``path`` (UTF-8, a leading BOM dropped), refusing files
    over ``max_bytes``, binary files (a NUL byte) and anything that is not a regular file."""
    path = Path(path)
    data = read_bytes(path, what, max_bytes=max_bytes)
    nul = data.find(b"\x00")
    if nul >= 0:
        raise InputDataError(f"{what} {path} is a binary file, not UTF-8 text (a NUL byte "
                             f"at offset {nul})")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputDataError(f"{what} {path} is not UTF-8 text ({exc.reason} at byte "
                             f"{exc.start})") from None


def check_text(text: str, where: str) -> str:
    """``text`` if it holds no unpaired UTF-16 surrogate (which JSON's ``\\ud800`` escapes
    can make and which no output can print), else :class:`InputDataError`."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise InputDataError(f"{where}: an unpaired UTF-16 surrogate "
                             f"({text[exc.start]!a}) in a string; give real characters") from None
    return text


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
        value = json.loads(text, parse_float=_finite_float, parse_int=_checked_int,
                           parse_constant=_reject_constant)
    except json.JSONDecodeError as exc:
        raise InputDataError(f"{where}, line {exc.lineno}: not valid JSON ({exc.msg})") from None
    except (ValueError, RecursionError) as exc:
        raise InputDataError(f"{where}: {exc}") from None
    if "\\u" in text or "\\U" in text:  # escapes are the only way to a lone surrogate
        check_text(json.dumps(value, ensure_ascii=False), where)
    return value


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


def check_output(path: str | Path, what: str = "output") -> Path:
    """``path`` if a file can be written there, checked before any work starts.

    Refused (:class:`~subtask_opt.base.errors.ParameterError`, one line naming the path
    and the reason): ``-`` (outputs are files, not standard output), a folder, a path that
    exists and is not a regular file (``/dev/full``, a FIFO), a path below a file, and a
    folder where nothing can be created (read-only, no space for a new name). A missing
    folder is created when the file is written (:func:`atomic_output`).
    """
    from subtask_opt.base.errors import ParameterError

    text = str(path)
    if text.strip() in ("", "-"):
        raise ParameterError(f"{what} {text!r}: give a file path (standard output is not "
                             "an output file)")
    path = Path(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        info = None
    except OSError as exc:
        raise ParameterError(f"{what} {path}: {exc.strerror or exc}") from None
    if info is not None and stat.S_ISDIR(info.st_mode):
        raise ParameterError(f"{what} {path} is a folder, not a file")
    if info is not None and not stat.S_ISREG(info.st_mode):
        raise ParameterError(f"{what} {path} exists and is not a regular file (a device, "
                             "pipe or socket); give a file path")
    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise ParameterError(f"{what} {path}: {folder} is a file, not a folder")
    try:  # the only test of writability that holds for root and read-only mounts alike
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".subtask-opt-probe-")
        os.close(fd)
        os.unlink(probe)
        space = os.statvfs(folder)
    except OSError as exc:
        raise ParameterError(f"{what} {path}: cannot write in {folder} "
                             f"({exc.strerror or exc})") from None
    free = space.f_bavail * space.f_frsize
    if free < MIN_FREE_BYTES:
        raise ParameterError(f"{what} {path}: no space left in {folder} ({free} bytes free, "
                             f"at least {MIN_FREE_BYTES} needed)")
    return path


@contextmanager
def atomic_output(path: str | Path, what: str = "output") -> Iterator[Path]:
    """A temporary path beside ``path`` (same suffix) to write to; renamed onto ``path``
    when the block ends without error, removed otherwise, so no partial file is left.

    A failed write (a full disk, a folder that became read-only) raises
    :class:`~subtask_opt.base.errors.ParameterError` naming ``path`` and the reason.
    """
    from subtask_opt.base.errors import ParameterError

    path = Path(path)
    tmp: Path | None = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem[:40]}.",
                                    suffix=f".part{path.suffix}")
        os.close(fd)
        tmp = Path(name)
        yield tmp
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, path)
        tmp = None
    except OSError as exc:
        raise ParameterError(f"cannot write {what} {path}: {exc.strerror or exc}") from None
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                tmp.unlink()


def write_text_atomic(path: str | Path, text: str, what: str = "output") -> None:
    """Write ``text`` (UTF-8) to ``path`` through :func:`atomic_output`."""
    with atomic_output(path, what) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
