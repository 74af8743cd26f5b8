"""Where numba keeps the package's compiled kernels, and when that copy is stale.

numba keys its on-disk cache on the file that defines a function only: edit a
kernel that others call and the callers keep running the old code. So the
cache lives in a folder named after a hash of every kernel source file of the
package: any edit to any of them selects a fresh folder, and folders unused for a
day are removed. Import this module before any module that defines a kernel (the
package's ``__init__`` does).

The root folder is ``$SUBTASK_OPT_CACHE_DIR`` or, by default,
``~/.cache/subtask_opt`` (``$XDG_CACHE_HOME`` is honoured); ``make clean`` and
``python -m subtask_opt._kernel_cache --clear`` remove it.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numba
from numba.core import event

PACKAGE_DIR = Path(__file__).resolve().parent
STALE_AFTER_S = 24 * 3600.0
"""A cache generation unused for this long is removed (others may still be in use)."""
_PREFIX = "kernels-"
KERNEL_OPT = 1
"""LLVM optimisation level of the package's kernels (numba's default, ``NUMBA_OPT``, is 3).

Level 1 runs the elbow-choosing search 1.65x faster than 3 and compiles 15% quicker, with
identical answers (measured in CONTRIBUTING, "Numba's cache and the cold start"). Set only
while numba compiles one of the package's kernels; a user's own kernels keep their level."""


def cache_root() -> Path:
    """The folder that holds every kernel-cache generation."""
    explicit = os.environ.get("SUBTASK_OPT_CACHE_DIR")
    if explicit:
        return Path(explicit).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "subtask_opt"


def kernel_sources() -> list[Path]:
    """Every source file of the package that defines a numba kernel, sorted."""
    return sorted(p for p in PACKAGE_DIR.rglob("*.py")
                  if "__pycache__" not in p.parts and b"@njit" in p.read_bytes())


def source_hash() -> str:
    """A short hash of the kernel sources (paths relative to the package, and contents)."""
    digest = hashlib.sha256(f"{numba.__version__} opt {KERNEL_OPT}".encode())
    for path in kernel_sources():
        digest.update(str(path.relative_to(PACKAGE_DIR)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def cache_dir() -> Path:
    """This source tree's cache folder."""
    return cache_root() / f"{_PREFIX}{source_hash()}"


def is_warm(group: str) -> bool:
    """Whether the kernels of ``group`` (e.g. ``"sequencing"``) were compiled for these sources."""
    return (CACHE_DIR / f"{group}.warm").exists()


def mark_warm(group: str) -> None:
    """Record that ``group``'s kernels are now in the cache."""
    try:
        (CACHE_DIR / f"{group}.warm").touch()
    except OSError:  # a read-only cache only costs recompilation
        pass


_announced = False


COMPILE_TIME_TEXT = ("about 1 minute for a planar arm's solve or batch and 1-2 more for a "
                     "serial arm's on 2 free cores, several times that when they are busy")
"""What a cold compile costs on the project's machine class (2 cores; measured in
CONTRIBUTING, "Numba's cache and the cold start"), said in the notice."""


def _announce(what: str) -> None:
    """Say once per process, on stderr (also into logs and pipes: the wait that
    follows is minutes), that numba is compiling, how long that takes, and where it
    is kept."""
    global _announced
    if not _announced:
        _announced = True
        where = (f"cached afterwards in {CACHE_DIR}" if _PRIVATE is None else
                 "not cached: the cache folder cannot be written")
        print(f"subtask-opt: compiling {what} (numba, once: {COMPILE_TIME_TEXT}; {where})",
              file=sys.stderr, flush=True)


def announce_if_empty(what: str) -> None:
    """The compile notice now, before the imports and set-up that precede the first kernel,
    when this source tree's cache holds no compiled kernel at all (a first run: everything
    will be compiled). Otherwise the notice waits for the first kernel numba must compile
    (:class:`_PackageCompiles`), if any."""
    if _announced:
        return
    try:
        empty = next(CACHE_DIR.rglob("*.nbi"), None) is None
    except OSError:
        empty = True
    if empty:
        _announce(what)


class _PackageCompiles(event.Listener):
    """Around numba's compilation (or cache load) of each of the package's kernels: sets
    :data:`KERNEL_OPT` for it (restored after), and announces the first kernel that must
    be compiled rather than loaded, whichever command or call starts it.

    numba compiles under one global lock, so the saved levels form a plain stack."""

    def __init__(self) -> None:
        self._saved: list[Any] = []

    def on_start(self, ev: event.Event) -> None:
        dispatcher = (ev.data or {}).get("dispatcher")
        module = getattr(getattr(dispatcher, "py_func", None), "__module__", None) or ""
        ours = module.startswith(f"{__package__}.")
        self._saved.append(numba.config.OPT)  # type: ignore[attr-defined]
        if not ours:
            return
        numba.config.OPT = type(numba.config.OPT)(KERNEL_OPT)  # type: ignore[attr-defined]
        if _announced:
            return
        try:  # numba has no public "is this cached": a missing index means a compile
            index = dispatcher._cache._cache_file._index_path  # type: ignore[union-attr]
        except AttributeError:
            return
        if not os.path.exists(index):
            _announce("the kernels this run needs")

    def on_end(self, ev: event.Event) -> None:
        if self._saved:
            numba.config.OPT = self._saved.pop()  # type: ignore[attr-defined]


LOCK_WAIT_S = 900.0
"""The longest wait for another process's compilation of a group (several cold compiles on a
busy machine); past it this process compiles the group itself, so a stopped holder cannot
hang it."""


@contextmanager
def _group_lock(group: str) -> Iterator[None]:
    """Hold ``group``'s lock file in the cache folder (exclusive, across processes).

    Two processes that start on a cold cache together (a batch's workers, a test run's)
    would otherwise both compile the same kernels, each for a minute; with the lock the
    second waits and then loads what the first saved. The wait polls (a signal such as
    Ctrl-C ends it at once) for at most :data:`LOCK_WAIT_S`. Where no lock can be taken
    (no ``fcntl``, an unwritable folder) or the wait runs out, the block runs unlocked,
    as before."""
    try:
        import fcntl

        handle = open(CACHE_DIR / f"{group}.lock", "a")  # noqa: SIM115 - held by the block
    except (ImportError, OSError):
        yield
        return
    try:
        deadline = time.monotonic() + LOCK_WAIT_S
        while True:
            try:  # released by close, or by the process's end
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() >= deadline:
                    break
                time.sleep(0.1)
            except OSError:  # a file system without locks
                break
        yield
    finally:
        handle.close()


@contextmanager
def compiling(group: str, what: str) -> Iterator[None]:
    """Around the first call of a group of kernels (``what``: how to name them).

    When ``group`` is not yet in the cache, the block holds the group's lock
    (:func:`_group_lock`: another process compiling the same group is waited for, and
    its kernels are then loaded), numba's compilation is announced once per process (if
    :class:`_PackageCompiles` has not already), and on a terminal a ticking elapsed-time
    bar follows. The group is marked warm after.
    """
    if is_warm(group):
        yield
        return
    with _group_lock(group):
        if is_warm(group):  # compiled by the process that held the lock
            yield
            return
        from subtask_opt.base.progress import elapsed_ticker

        _announce(what)
        with elapsed_ticker(f"compiling {what}"):
            yield
        mark_warm(group)


class _LockCPU(event.Listener):
    """CPU seconds this thread spends holding (or waiting for) numba's compiler lock."""

    def __init__(self) -> None:
        self._thread = threading.get_ident()
        self._depth = 0
        self._t0 = 0.0
        self.seconds = 0.0

    def on_start(self, ev: event.Event) -> None:
        if threading.get_ident() != self._thread:
            return
        if self._depth == 0:
            self._t0 = time.process_time()
        self._depth += 1

    def on_end(self, ev: event.Event) -> None:
        if threading.get_ident() != self._thread or self._depth == 0:
            return
        self._depth -= 1
        if self._depth == 0:
            self.seconds += time.process_time() - self._t0


@contextmanager
def compile_seconds() -> Iterator[list[float]]:
    """CPU seconds numba spends compiling or loading compiled code inside the block: the
    yielded list receives that one number when the block ends, so a phase's CPU time
    can be reported without the first run's compilation.

    Measured around numba's compiler lock, which covers loading a kernel from the cache
    as well as compiling it (numba's ``numba:compile`` event covers compilation only:
    the first leg matrix of a process hid about 1.9 s of loading), in CPU seconds of
    the calling thread's process (the clock the phases use: wall seconds would take a
    busy machine's waiting out of the phase as well)."""
    listener = _LockCPU()
    spent: list[float] = []
    with event.install_listener("numba:compiler_lock", listener):
        yield spent
    spent.append(listener.seconds)


@contextmanager
def compile_apart(cpu: dict[str, float]) -> Iterator[list[float]]:
    """numba's compilation inside the block into ``cpu["compile"]`` (a first run's
    compile is not the work of the phase around it); the yielded list receives those CPU
    seconds, for the phase the block belongs to to leave out."""
    t0 = time.process_time()
    spent: list[float] = []
    with compile_seconds() as compiled:
        yield spent
    spent.append(min(compiled[0], time.process_time() - t0))
    cpu["compile"] = cpu.get("compile", 0.0) + spent[0]


def clear() -> Path:
    """Remove every cached generation; return the folder that was cleared."""
    root = cache_root()
    shutil.rmtree(root, ignore_errors=True)
    return root


MIN_FREE_BYTES = 16 << 20
"""A cache folder with less free space is treated as unwritable (a kernel file is ~1 MiB)."""


def _writable(folder: Path) -> str | None:
    """Why nothing can be cached in ``folder`` (None: it can)."""
    import tempfile

    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".probe-")
        os.close(fd)
        os.unlink(probe)
        space = os.statvfs(folder)
    except OSError as exc:
        return exc.strerror or str(exc)
    if space.f_bavail * space.f_frsize < MIN_FREE_BYTES:
        return f"{space.f_bavail * space.f_frsize} bytes free"
    return None


_PRIVATE: Path | None = None
"""The temporary cache folder used when the real one cannot be written (else None)."""


def _private_folder() -> Path:
    """A temporary cache folder of this process alone, removed at exit."""
    import atexit
    import tempfile

    global _PRIVATE
    folder = Path(tempfile.mkdtemp(prefix="subtask_opt-kernels-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    _PRIVATE = folder
    return folder


def _activate() -> Path:
    """Point numba at this source tree's cache folder.

    A folder that cannot be written (read-only, full, not creatable) would make numba
    fall back to ``__pycache__`` beside the sources, where the source hash no longer
    guards it; instead this process compiles into a private temporary folder (removed at
    exit), after one warning line on stderr.
    """
    folder = cache_dir()
    why = _writable(folder)
    if why is None:
        try:
            folder.touch()  # mark it in use
            for old in folder.parent.glob(f"{_PREFIX}*"):
                # another checkout or process may still use a recent one: remove only old ones
                if old != folder and time.time() - old.stat().st_mtime > STALE_AFTER_S:
                    shutil.rmtree(old, ignore_errors=True)
        except OSError:
            pass
    else:
        try:
            private = _private_folder()
        except OSError:  # nowhere to write at all: numba compiles in memory
            private = folder
        print(f"subtask-opt: warning: cannot use the kernel cache {folder} ({why}); "
              "compiling in memory for this run only", file=sys.stderr, flush=True)
        folder = private
    numba.config.CACHE_DIR = str(folder)  # type: ignore[attr-defined]
    return folder


CACHE_DIR = _activate()
event.register("numba:compile", _PackageCompiles())

if __name__ == "__main__":  # pragma: no cover - make clean
    if sys.argv[1:] == ["--clear"]:
        print(f"removed {clear()}")
    else:
        print(CACHE_DIR)
