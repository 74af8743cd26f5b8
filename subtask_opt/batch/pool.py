"""Run one function over many items: in this process, a process pool or a Dask cluster.

:func:`map_jobs` is the generic helper behind :func:`subtask_opt.batch.solve_many`;
any suite with independent jobs (reactive or AGV scenarios, benchmark seeds) can
use it the same way::

    from subtask_opt.batch import map_jobs

    def run_one(seed: int) -> float:          # module level: workers import it
        ...

    costs = map_jobs(run_one, range(100), workers=4)              # local processes
    costs = map_jobs(run_one, range(100), scheduler="tcp://head:8786")  # a cluster

Where the items run:

* ``scheduler`` given (an address ``"tcp://host:port"`` or a
  ``distributed.Client``): on that existing dask.distributed cluster; needs
  ``pip install subtask_opt[cluster]``.
* ``workers=0``: one after another in this process (no pool; a debugger works).
* ``workers=N`` (default: the machine's cores): a local Dask cluster of N worker
  processes (one thread each) when dask.distributed is installed, else a
  ``concurrent.futures.ProcessPoolExecutor`` of N processes. Both give the same
  results; only the cluster re-runs the jobs of a worker that dies.

``fn`` must be picklable (a module-level function or a ``functools.partial`` of
one) and so must the items and the results. Items travel in chunks (a few per
task) so that the scheduler's round trip per task is shared by several items.
``warm_up`` runs once in every worker process before its first job (numba
kernels load or compile there, not inside a timed job): a Dask ``WorkerPlugin``
on a cluster, which also warms workers that join or restart later, and the
pool's initializer otherwise.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import os
import uuid
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from multiprocessing import get_context
from typing import Any, TypeVar

from subtask_opt.base.errors import ParameterError, require_int
from subtask_opt.base.progress import progress_bar

T = TypeVar("T")
R = TypeVar("R")

INSTALL_HINT = "pip install subtask_opt[cluster]"
"""What to install for the Dask backend (``dask[distributed]``)."""

MAX_WORKERS = 4096
"""The largest ``workers`` accepted (a typo guard, not a hardware limit)."""

KEY_PREFIX = "subtask_opt-jobs"
"""Dask task keys are ``f"{KEY_PREFIX}-{batch}-{start}-{stop}"`` (items ``start:stop``)."""


def dask_available() -> bool:
    """Whether ``dask.distributed`` can be imported (the ``cluster`` extra)."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


def default_workers() -> int:
    """The number of worker processes used when none is given: the machine's cores."""
    return max(1, os.cpu_count() or 1)


def job_indices(key: Any) -> range | None:
    """The item indices of a Dask task key made by :func:`map_jobs` (None for other keys)."""
    parts = str(key).split("-")
    prefix = KEY_PREFIX.split("-")
    if parts[:len(prefix)] != prefix or len(parts) != len(prefix) + 3:
        return None
    start, stop = parts[-2:]
    return range(int(start), int(stop)) if start.isdigit() and stop.isdigit() else None


def map_jobs(fn: Callable[[T], R], items: Iterable[T], *, workers: int | None = None,
             scheduler: Any = None, retries: int = 2, chunksize: int | None = None,
             warm_up: Callable[[], None] | None = None,
             on_result: Callable[[int, Any], None] | None = None,
             return_exceptions: bool = False, progress: bool = False,
             desc: str = "jobs", isolate: bool = False,
             timeout: float | None = None) -> list[Any]:
    """``[fn(item) for item in items]``, run in parallel; results in input order.

    Args:
        fn: a picklable function of one item.
        items: the inputs (materialised into a list first).
        workers: ``0`` runs here, serially; ``N >= 1`` runs on N local worker
            processes (Dask when installed, else a process pool); default: the
            machine's cores. Not together with ``scheduler``.
        scheduler: an existing dask.distributed cluster: its address
            (``"tcp://host:port"``) or a ``distributed.Client`` (left open).
        retries: (Dask) times a task that raised is re-run before it counts as
            failed. Tasks of a worker that dies are re-assigned by the scheduler
            itself (up to ``distributed.scheduler.allowed-failures`` deaths).
        chunksize: items per task sent to a worker (each task costs a round
            trip to the scheduler); default: at most :data:`MAX_CHUNK`, and
            at least four tasks per worker. A dead worker's whole chunk re-runs.
        warm_up: run once per worker process before its first item.
        on_result: called as ``on_result(index, value)`` in the calling thread
            as each item finishes (in completion order; the items of one
            chunk together), e.g. to stream output.
        return_exceptions: put an item's exception in its slot of the result
            list (and pass it to ``on_result``) instead of raising it; the
            other items still run.
        progress: a progress bar on stderr (only on a terminal).
        desc: the progress bar's label.
        isolate: run every item in its own process forked from the worker (POSIX), so
            that an item that crashes its process fails alone (:class:`JobCrashed`)
            instead of taking the worker and its other items down.
        timeout: (needs ``isolate``) seconds an item may run before it is stopped and
            fails with :class:`JobTimeout`; at most :data:`MAX_TIMEOUT_S`.

    Raises:
        ParameterError: bad ``workers``/``retries``/``chunksize``, both
            ``workers`` and ``scheduler``, a scheduler without dask installed
            (the message says what to install), or a scheduler that cannot be
            reached.

    A script that calls this with ``workers >= 1`` must guard its entry point
    with ``if __name__ == "__main__":`` (worker processes are spawned and
    import the main module, as with :mod:`multiprocessing`).
    """
    require_int("map_jobs", "retries", retries, 0, 100)
    if timeout is not None:
        from subtask_opt.base.errors import require_in_range

        require_in_range("map_jobs", "timeout", timeout, 0.0, MAX_TIMEOUT_S)
        if timeout <= 0:
            raise ParameterError(f"map_jobs.timeout must be > 0, got {timeout!r}")
        if not isolate:
            raise ParameterError("map_jobs: timeout needs isolate=True (a job is stopped by "
                                 "killing its own process)")
    if chunksize is not None:
        require_int("map_jobs", "chunksize", chunksize, 1)
    if workers is not None:
        require_int("map_jobs", "workers", workers, 0, MAX_WORKERS)
        if scheduler is not None:
            raise ParameterError(
                f"map_jobs: give workers (got {workers!r}) or a scheduler (got {scheduler!r}), "
                "not both")
    items = list(items)
    results: list[Any] = [None] * len(items)
    if not items:
        return results
    with progress_bar(progress, total=len(items), desc=desc, unit="job") as bar:
        failed = [0]

        def done(index: int, value: Any) -> None:
            results[index] = value
            if isinstance(value, BaseException):
                failed[0] += 1
                bar.set_postfix_str(f"{failed[0]} failed")
            bar.update(1)
            if on_result is not None:
                on_result(index, value)

        run = _Runner(functools.partial(_run_chunk, fn, isolate=isolate, timeout=timeout),
                      items, done, retries=retries, chunksize=chunksize, warm_up=warm_up,
                      return_exceptions=return_exceptions)
        if scheduler is not None:
            run.on_dask(scheduler)
        else:
            n = default_workers() if workers is None else workers
            if n == 0:
                run.serial()
            elif dask_available():
                run.on_local_dask(n)
            else:
                run.on_process_pool(n)
    return results


MAX_CHUNK = 8
"""The largest number of items one task carries by default."""


def chunk_size(items: int, slots: int) -> int:
    """Items per task: at least four tasks per worker slot, at most :data:`MAX_CHUNK` items."""
    return max(1, min(MAX_CHUNK, items // (4 * max(1, slots))))


class JobTimeout(TimeoutError):
    """A job ran past ``map_jobs``'s per-job ``timeout`` and was stopped."""


class JobCrashed(RuntimeError):
    """The process running a job died (a signal, ``os._exit``, out of memory)."""


MAX_TIMEOUT_S = 7 * 86_400.0
"""The longest per-job ``timeout`` accepted (a week)."""

_FORKED_FROM: int | None = None


def worker_pid() -> int:
    """The pid of the worker running this job (its own pid, or the worker's when the job
    runs in a process forked for it)."""
    return _FORKED_FROM if _FORKED_FROM is not None else os.getpid()


def _run_chunk(fn: Callable[[Any], Any], chunk: list[Any], isolate: bool = False,
               timeout: float | None = None) -> list[tuple[bool, Any]]:
    """``fn`` over a chunk, in a worker: ``(True, value)`` or ``(False, exception)`` each.

    ``isolate``: each item runs in a process forked from the worker (which has its
    kernels loaded already, so the fork costs milliseconds): a job that crashes that
    process, or runs past ``timeout`` seconds and is killed, fails alone
    (:class:`JobCrashed`, :class:`JobTimeout`) and the worker goes on.
    """
    out: list[tuple[bool, Any]] = []
    for item in chunk:
        if isolate and hasattr(os, "fork"):
            out.append(_run_forked(fn, item, timeout))
            continue
        try:
            out.append((True, fn(item)))
        except Exception as exc:
            out.append((False, exc))
    return out


def _run_forked(fn: Callable[[Any], Any], item: Any,
                timeout: float | None) -> tuple[bool, Any]:
    """``fn(item)`` in a forked child; its pickled outcome comes back through a pipe."""
    import pickle
    import selectors
    import signal
    import time

    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: run, send, leave without running the parent's exit handlers
        os.close(read_fd)
        code = 0
        try:
            global _FORKED_FROM
            _FORKED_FROM = os.getppid()
            with contextlib.suppress(ValueError):  # the parent decides on Ctrl-C
                signal.signal(signal.SIGINT, signal.SIG_IGN)
            _die_with_parent(_FORKED_FROM)
            try:
                outcome: tuple[bool, Any] = (True, fn(item))
            except Exception as exc:  # noqa: BLE001 - travels to the parent
                outcome = (False, exc)
            try:
                data = pickle.dumps(outcome, protocol=pickle.HIGHEST_PROTOCOL)
            except Exception as exc:  # noqa: BLE001 - an unpicklable value or exception
                data = pickle.dumps((False, RuntimeError(f"{type(exc).__name__}: {exc}")))
            view = memoryview(data)
            while view:
                view = view[os.write(write_fd, view):]
        except BaseException:  # noqa: BLE001
            code = 1
        finally:
            os._exit(code)
    os.close(write_fd)
    chunks: list[bytes] = []
    deadline = None if timeout is None else time.monotonic() + timeout
    timed_out = False
    with selectors.DefaultSelector() as sel:
        sel.register(read_fd, selectors.EVENT_READ)
        try:
            while True:
                wait = None if deadline is None else deadline - time.monotonic()
                if wait is not None and wait <= 0:
                    timed_out = True
                    break
                if not sel.select(wait):
                    continue
                block = os.read(read_fd, 1 << 20)
                if not block:
                    break
                chunks.append(block)
        except BaseException:  # Ctrl-C in the worker: take the child down too
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            os.close(read_fd)
            raise
    os.close(read_fd)
    if timed_out:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        return False, JobTimeout(f"the job ran past the per-job time limit of {timeout:g} s "
                                 "and was stopped")
    _, status = os.waitpid(pid, 0)
    if chunks:
        try:
            return pickle.loads(b"".join(chunks))
        except Exception as exc:  # noqa: BLE001 - a truncated message: the child died
            return False, JobCrashed(f"the job's process died while reporting ({exc})")
    if os.WIFSIGNALED(status):
        number = os.WTERMSIG(status)
        try:
            name = signal.Signals(number).name
        except ValueError:
            name = str(number)
        return False, JobCrashed(f"the job's process was killed by {name}")
    return False, JobCrashed(f"the job's process exited with code {os.WEXITSTATUS(status)} "
                             "without a result")


def _die_with_parent(parent: int) -> None:
    """(Linux) Kill this forked job when the process that forked it ends, e.g. a worker
    stopped on Ctrl-C: an orphaned job would run on and hold the parent's output pipes."""
    import ctypes
    import signal

    with contextlib.suppress(OSError, AttributeError):
        pr_set_pdeathsig = 1
        ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, int(signal.SIGKILL))
    if os.getppid() != parent:  # the parent ended before the request took effect
        os._exit(1)


def _ignore_sigint(warm_up: Callable[[], None] | None) -> None:
    """A local worker's initializer: Ctrl-C reaches the whole process group, and only the
    parent (which stops the pool and prints one line) should act on it."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if warm_up is not None:
        warm_up()


class _Runner:
    """One map_jobs call: the items, their chunks and where the results go."""

    def __init__(self, run_chunk: Callable[[list[Any]], list[tuple[bool, Any]]],
                 items: list[Any], done: Callable[[int, Any], None], *, retries: int,
                 chunksize: int | None, warm_up: Callable[[], None] | None,
                 return_exceptions: bool) -> None:
        self.run_chunk, self.items, self.done = run_chunk, items, done
        self.retries, self.chunksize, self.warm_up = retries, chunksize, warm_up
        self.return_exceptions = return_exceptions

    def chunks(self, slots: int) -> list[range]:
        size = self.chunksize or chunk_size(len(self.items), slots)
        return [range(i, min(i + size, len(self.items))) for i in range(0, len(self.items), size)]

    def deliver(self, indices: range, outcome: list[tuple[bool, Any]] | BaseException) -> None:
        """Hand a finished chunk's values (or the exception that lost it) to ``done``."""
        if isinstance(outcome, BaseException):
            outcome = [(False, outcome)] * len(indices)
        for index, (ok, value) in zip(indices, outcome, strict=True):
            if not ok and not self.return_exceptions:
                raise value
            self.done(index, value)

    def serial(self) -> None:
        if self.warm_up is not None:
            self.warm_up()
        for index, item in enumerate(self.items):
            self.deliver(range(index, index + 1), self.run_chunk([item]))

    def on_process_pool(self, workers: int) -> None:
        # spawn, not fork: the parent may hold threads (a Dask client, numba's pool) and locks
        pool = ProcessPoolExecutor(max_workers=min(workers, len(self.items)),
                                   mp_context=get_context("spawn"),
                                   initializer=_ignore_sigint, initargs=(self.warm_up,))
        pending = {pool.submit(self.run_chunk, [self.items[i] for i in r]): r
                   for r in self.chunks(workers)}
        try:
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    indices = pending.pop(future)
                    exc = future.exception()  # the pool broke (a worker died)
                    self.deliver(indices, future.result() if exc is None else exc)
        except BaseException:  # Ctrl-C or a raised job: stop the workers, do not wait
            for future in pending:
                future.cancel()
            for proc in list(getattr(pool, "_processes", {}).values()):
                proc.kill()
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown(wait=True)

    def on_local_dask(self, workers: int) -> None:
        import logging

        from distributed import Client, LocalCluster

        # dashboard on a free port: the scheduler's HTTP server starts anyway, 8787 may be taken
        saved: dict[str, int] = {}
        try:
            with LocalCluster(n_workers=min(workers, len(self.items)), threads_per_worker=1,
                              processes=True, dashboard_address=":0",
                              silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
                try:
                    self.submit_all(client)
                except BaseException:
                    # Ctrl-C or a raised job: the cluster closes with tasks running, and its
                    # nannies log the cancelled ones as errors (tracebacks on stderr)
                    for name in [n for n in logging.root.manager.loggerDict
                                 if n.split(".")[0] == "distributed"] + ["distributed"]:
                        saved[name] = logging.getLogger(name).level
                        logging.getLogger(name).setLevel(logging.CRITICAL + 1)
                    raise
        finally:
            for name, level in saved.items():
                logging.getLogger(name).setLevel(level)

    def on_dask(self, scheduler: Any) -> None:
        if not dask_available():
            raise ParameterError(
                f"running on the dask scheduler {scheduler!r} needs dask.distributed: "
                f"{INSTALL_HINT}")
        from distributed import Client

        if isinstance(scheduler, Client):
            self.submit_all(scheduler)
            return
        if not isinstance(scheduler, str) or "://" not in scheduler:
            raise ParameterError(
                f"scheduler must be an address like 'tcp://host:8786' or a distributed.Client, "
                f"got {scheduler!r}")
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise ParameterError(
                f"cannot connect to the dask scheduler {scheduler!r}: {exc}") from None
        with client:
            self.submit_all(client)

    def submit_all(self, client: Any) -> None:
        from distributed import as_completed

        if self.warm_up is not None:
            # one name per warm-up: registering it again (a second batch) is a no-op
            client.register_plugin(_warm_up_plugin(self.warm_up),
                                   name=f"subtask_opt-warm-up-{_token(self.warm_up)}")
        batch = uuid.uuid4().hex[:12]
        chunks = self.chunks(sum(client.nthreads().values()))
        futures = client.map(self.run_chunk, [[self.items[i] for i in r] for r in chunks],
                             key=[f"{KEY_PREFIX}-{batch}-{r.start}-{r.stop}" for r in chunks],
                             retries=self.retries, pure=False)
        chunk_of = {f.key: r for f, r in zip(futures, chunks, strict=True)}
        try:
            for future in as_completed(futures):
                try:
                    outcome = future.result()
                except Exception as exc:  # its workers kept dying, or it could not unpickle
                    outcome = exc
                self.deliver(chunk_of[future.key], outcome)
        finally:
            client.cancel([f for f in futures if not f.done()])


def _token(fn: Callable[[], None]) -> str:
    """A stable name for a warm-up callable (its function and arguments)."""
    if isinstance(fn, functools.partial):
        return f"{_token(fn.func)}{fn.args!r}{sorted(fn.keywords.items())!r}"
    return f"{getattr(fn, '__module__', '')}.{getattr(fn, '__qualname__', repr(fn))}"


def _warm_up_plugin(warm_up: Callable[[], None]) -> Any:
    """A Dask WorkerPlugin running ``warm_up`` once on every worker (current and future)."""
    from distributed.diagnostics.plugin import WorkerPlugin

    class WarmUp(WorkerPlugin):
        idempotent = True

        def __init__(self, fn: Callable[[], None]) -> None:
            self.fn = fn

        async def setup(self, worker: Any) -> None:
            # off the worker's event loop: a cold numba cache compiles for a while
            await asyncio.get_running_loop().run_in_executor(None, self.fn)

    return WarmUp(warm_up)


__all__ = ["INSTALL_HINT", "KEY_PREFIX", "MAX_CHUNK", "MAX_TIMEOUT_S", "JobCrashed",
           "JobTimeout", "chunk_size", "dask_available", "default_workers", "job_indices",
           "map_jobs"]
