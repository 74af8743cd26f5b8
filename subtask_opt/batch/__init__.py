"""Batches of independent jobs on many cores or a Dask cluster.

* :func:`solve_many` solves many sequencing jobs (:class:`Job` descriptions or
  ready :class:`~subtask_opt.PlanarProblem` objects) and returns one
  :class:`JobResult` each; a failed job reports its error, the others run on.
* :func:`map_jobs` is the generic helper underneath: any picklable function
  over a list of items, in this process, on local worker processes or on an
  existing dask.distributed cluster (``pip install subtask_opt[cluster]``).
* :func:`suite_mapper` runs the planners' benchmark suites (AGV, reactive) the
  same way.
"""

from subtask_opt.batch.jobs import Job, JobResult, load_jobs, overhead_per_job, solve_many, warm_up
from subtask_opt.batch.pool import INSTALL_HINT, dask_available, default_workers, map_jobs
from subtask_opt.batch.suites import suite_mapper, warm_agv, warm_reactive

__all__ = ["INSTALL_HINT", "Job", "JobResult", "dask_available", "default_workers", "load_jobs",
           "map_jobs", "overhead_per_job", "solve_many", "suite_mapper", "warm_agv",
           "warm_reactive", "warm_up"]
