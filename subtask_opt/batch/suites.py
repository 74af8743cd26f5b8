"""The benchmark suites on many cores or a Dask cluster: one mapper for every suite.

The suites of the planners (:func:`~subtask_opt.planners.agv.scenarios.run_agv_suite`,
:func:`~subtask_opt.planners.reactive.simulation.benchmark_navigators`) take a
``map_runs(fn, items)`` callable and know nothing of Dask; :func:`suite_mapper`
builds one from the same options as ``subtask-opt batch``::

    from subtask_opt.batch import suite_mapper
    from subtask_opt.planners.agv.scenarios import run_agv_suite

    report = run_agv_suite(200, 0, map_runs=suite_mapper(workers=2, warm_up=warm_agv))

Every run of a suite depends on its own seed only, so the report is the same
on one worker, on a local Dask cluster, on the process-pool fallback and on a
remote cluster (the wall-time fields aside).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from subtask_opt.batch.pool import map_jobs

Mapper = Callable[[Callable[[Any], Any], list[Any]], list[Any]]
"""``map_runs(fn, items) -> [fn(item) for item in items]``, in input order."""

_WARM: set[str] = set()


def warm_agv() -> None:
    """Load (or compile) the AGV simulation's kernels once per process: one short run."""
    if "agv" in _WARM:
        return
    from subtask_opt.planners.agv.scenarios import agv_suite_run, suite_params

    agv_suite_run(10_000, suite_params())
    _WARM.add("agv")


def warm_reactive() -> None:
    """Load (or compile) the reactive navigators' kernels once per process: one run each."""
    if "reactive" in _WARM:
        return
    from subtask_opt.planners.reactive.simulation import benchmark_navigators

    benchmark_navigators(1, 10_000)
    _WARM.add("reactive")


def suite_mapper(*, workers: int | None = None, scheduler: Any = None, progress: bool = False,
                 desc: str = "runs", warm_up: Callable[[], None] | None = None) -> Mapper:
    """A ``map_runs`` for the suites, running on :func:`~subtask_opt.batch.map_jobs`.

    Args:
        workers: ``0`` runs here; ``N`` local worker processes (Dask when
            installed, else a process pool); default: the machine's cores.
        scheduler: an existing dask.distributed cluster (address or Client).
        progress: a progress bar of finished runs (only on a terminal).
        desc: the progress bar's label.
        warm_up: run once in every worker before its first run
            (:func:`warm_agv`, :func:`warm_reactive`).

    A run that raises stops the suite with its exception, as in a serial loop.
    The options are checked when the mapper runs (:func:`map_jobs` raises
    :class:`~subtask_opt.base.errors.ParameterError`).
    """
    def run(fn: Callable[[Any], Any], items: list[Any]) -> list[Any]:
        return map_jobs(fn, items, workers=workers, scheduler=scheduler, progress=progress,
                        desc=desc, warm_up=warm_up)

    return run


__all__ = ["Mapper", "suite_mapper", "warm_agv", "warm_reactive"]
