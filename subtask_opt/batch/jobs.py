"""Many sequencing jobs at once: :func:`solve_many`, :class:`Job`, :class:`JobResult`.

A plant sequences hundreds of part variants, each with its own subtask file::

    from subtask_opt.batch import Job, solve_many

    jobs = [Job(f"part{i}", f"parts/part{i}.csv", time_model="joint") for i in range(300)]
    results = solve_many(jobs, seeds=None, workers=8)            # 8 local processes
    results = solve_many(jobs, seeds=None, client="tcp://head:8786")  # a Dask cluster

A failed job (unreadable file, unreachable subtask, ...) gives a
:class:`JobResult` with ``success=False`` and its error; the others run on.
Subtask files are read here, on the calling machine, so the workers of a remote
cluster need no access to them; robots given as URDF paths must be readable on
the workers (robot names need nothing), and the workers need the same
subtask_opt installed. A script that starts local workers (``workers >= 1``)
must guard its entry point with ``if __name__ == "__main__":``.
"""

from __future__ import annotations

import math
import pickle
import socket
import sys
import time
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, fields, replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from subtask_opt.arm.planar_problem import (
    DEFAULT_TIME_MODEL,
    PlanarProblem,
    default_configurations,
    solve,
)
from subtask_opt.arm.poses import load_targets
from subtask_opt.arm.tasks import CASE_NAMES, load_subtasks
from subtask_opt.arm.timing.models import TIME_MODELS
from subtask_opt.base.errors import (
    InputDataError,
    ParameterError,
    SubtaskOptError,
    require_in_range,
    require_int,
)
from subtask_opt.base.files import check_input_file, parse_json, read_text
from subtask_opt.batch.pool import map_jobs
from subtask_opt.tour.constraints import TourConstraints
from subtask_opt.tour.problem import MatrixProblem
from subtask_opt.tour.solve import SolverParams

if TYPE_CHECKING:
    from subtask_opt.base.stop import StoppingCriterion

SEED_MAX = 2**63 - 1
"""The largest seed a job takes (the CLI's ``--seed`` range)."""

CONFIGURATIONS = ("fixed", "optimize")
LINE_FALLBACKS = ("joint", "exclude")


@dataclass(frozen=True)
class Job:
    """One sequencing job: which subtasks, on which robot, under which time model.

    Attributes:
        id: a name unique within the batch (results and JSON are keyed by it).
        case: a built-in case name (``square20``, ``random30``) or the path of
            a subtask file (CSV with header ``x,y[,theta]`` or JSON).
        robot: a robot name or a URDF path (see :func:`subtask_opt.load_planar_arm`).
        time_model: ``joint`` (the library's default), ``line``, ``trapezoid``
            or ``paper``.
        seed: the solver's seed.
        case_seed: the seed of the ``random30`` generator.
        first: index of the subtask the tour starts at (default: the first).
        k: via-point fraction of the paper's time model, in [0, 0.5).
        elbow: IK branch at every subtask with fixed configurations (0 or 1).
        configurations: ``"fixed"`` or ``"optimize"``; default (None): the
            model's default (``optimize`` for the joint and line models).
        line_fallback: (line model) ``"joint"`` or ``"exclude"``.
        home: a planar arm's home point ``(x, y)`` (m), visited first and last; a serial
            arm's home configuration in degrees (default: the robot file's).
        scene, standoff, axis_step, tool_frame: (serial arms) the cell's scene file, the
            tool standoff (m), the sampling step about a tool axis (degrees) and the tool
            frame (see ``subtask-opt solve``).
        detours: (serial arms) plan legs whose straight joint motion collides around the
            obstacles (:mod:`subtask_opt.cell.detour`); False forbids them (``solve
            --no-detours``, ``batch --no-detours``).

    A serial arm's job (a robot that is not a planar 2R arm) takes a target file and the
    joint model; a planar option given to it, or a serial option to a planar arm, is
    refused.
    """

    id: str
    case: str | Path
    robot: str = "planar_2r"
    time_model: str = DEFAULT_TIME_MODEL
    seed: int = 0
    case_seed: int = 0
    first: int | None = None
    k: float = 0.1
    elbow: int = 0
    configurations: str | None = None
    line_fallback: str = "joint"
    home: tuple[float, ...] | None = None
    scene: str | None = None
    standoff: float = 0.0
    axis_step: float = 45.0
    tool_frame: str | None = None
    detours: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not self.id.strip():
            raise ParameterError(f"Job.id must be a non-empty string, got {self.id!r}")
        if not isinstance(self.case, (str, Path)) or not str(self.case).strip():
            raise ParameterError(
                f"Job.case must be one of {', '.join(CASE_NAMES)} or a subtask file path, "
                f"got {self.case!r}")
        if not isinstance(self.robot, str) or not self.robot.strip():
            raise ParameterError(
                f"Job.robot must be a robot name or a URDF path, got {self.robot!r}")
        if self.time_model not in TIME_MODELS:
            raise ParameterError(f"Job.time_model must be one of {', '.join(TIME_MODELS)}, "
                                 f"got {self.time_model!r}")
        require_int("Job", "seed", self.seed, 0, SEED_MAX)
        require_int("Job", "case_seed", self.case_seed, 0, SEED_MAX)
        if self.first is not None:
            require_int("Job", "first", self.first, 0)
        require_in_range("Job", "k", self.k, 0.0, 0.5)
        if self.k >= 0.5:
            raise ParameterError(f"Job.k must be < 0.5, got {self.k!r}")
        if self.elbow not in (0, 1) or isinstance(self.elbow, bool):
            raise ParameterError(f"Job.elbow must be 0 or 1, got {self.elbow!r}")
        if self.configurations is not None and self.configurations not in CONFIGURATIONS:
            raise ParameterError(f"Job.configurations must be one of "
                                 f"{', '.join(CONFIGURATIONS)} or None, "
                                 f"got {self.configurations!r}")
        if self.line_fallback not in LINE_FALLBACKS:
            raise ParameterError(f"Job.line_fallback must be one of {', '.join(LINE_FALLBACKS)}, "
                                 f"got {self.line_fallback!r}")
        if self.home is not None:
            try:
                home = tuple(float(v) for v in self.home)
            except (TypeError, ValueError):
                raise ParameterError(f"Job.home must be a list of numbers, got "
                                     f"{self.home!r}") from None
            if not home or not all(math.isfinite(v) and abs(v) <= 1e4 for v in home):
                raise ParameterError(f"Job.home must hold finite numbers in [-1e4, 1e4], got "
                                     f"{self.home!r}")
            object.__setattr__(self, "home", home)
        require_in_range("Job", "standoff", self.standoff, -1.0, 1.0)
        require_in_range("Job", "axis_step", self.axis_step, 5.0, 360.0)
        for name in ("scene", "tool_frame"):
            value = getattr(self, name)
            if value is not None and (not isinstance(value, str) or not value.strip()):
                raise ParameterError(f"Job.{name} must be a non-empty string, got {value!r}")
        if not isinstance(self.detours, bool):
            raise ParameterError(f"Job.detours must be true or false, got {self.detours!r}")
        defaults = {f.name: f.default for f in fields(self)}
        serial = self.serial
        wrong = (("time_model", "case_seed", "first", "k", "elbow", "configurations",
                  "line_fallback") if serial else ("scene", "standoff", "axis_step",
                                                   "tool_frame", "detours"))
        for name in wrong:
            value = getattr(self, name)
            if value != defaults[name] and not (name == "time_model" and value == "joint"):
                raise ParameterError(f"Job.{name} applies to {'planar' if serial else 'serial'}"
                                     f" arms only; {self.robot} is "
                                     f"{'a serial' if serial else 'a planar'} arm")
        if serial and self.builtin:
            raise ParameterError(f"Job.case {self.case!r} is a planar built-in case; a serial "
                                 f"arm ({self.robot}) takes a target file")
        if not serial and self.home is not None and len(self.home) != 2:
            raise ParameterError(f"Job.home of a planar arm is a point (x, y), got "
                                 f"{len(self.home)} numbers")

    @property
    def serial(self) -> bool:
        """Whether the robot is a serial arm (not a planar 2R arm)."""
        from subtask_opt.arm.problem import movable_joints
        from subtask_opt.kinematics.planar import ROBOT_NAMES

        if self.robot in ROBOT_NAMES:
            return False
        return not (self.robot.lower().endswith(".urdf") and movable_joints(self.robot) == 2)

    @property
    def builtin(self) -> bool:
        """Whether :attr:`case` names a built-in case (else it is a file)."""
        return isinstance(self.case, str) and self.case in CASE_NAMES

    @property
    def configuration_mode(self) -> str:
        """The configurations mode the job is solved with (the default resolved)."""
        return self.configurations or default_configurations(self.time_model)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (one entry of a manifest)."""
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["case"] = str(self.case)
        out["home"] = None if self.home is None else list(self.home)
        return out

    @classmethod
    def from_dict(cls, data: Any, *, base_dir: str | Path | None = None,
                  where: str = "job") -> Job:
        """A job from a manifest entry; relative file cases are taken from ``base_dir``.

        Raises:
            InputDataError: not an object, an unknown key, or a bad value
                (the message starts with ``where``).
        """
        if not isinstance(data, dict):
            raise InputDataError(f"{where}: expected an object with id and case, got {data!r}")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise InputDataError(f"{where}: unknown key {unknown[0]!r} (allowed: "
                                 f"{', '.join(f.name for f in fields(cls))})")
        for key in ("id", "case"):
            if key not in data:
                raise InputDataError(f"{where}: missing {key!r}")
        values = dict(data)
        case = values["case"]
        if isinstance(case, str) and case not in CASE_NAMES and base_dir is not None:
            path = Path(case)
            values["case"] = str(path if path.is_absolute() else Path(base_dir) / path)
        try:
            return cls(**values)
        except ParameterError as exc:
            raise InputDataError(f"{where}: {exc}") from None


@dataclass(frozen=True)
class JobResult:
    """What one job of :func:`solve_many` gave.

    Attributes:
        id: the job's id (``"problem-<index>"`` for a ready problem).
        success: whether the job was solved.
        error: why it failed (``"<ErrorType>: <message>"``), None on success.
        total_time: time of the closed tour (s); None on failure.
        order: the tour (0-based subtask indices); None on failure.
        runtime_s: the solver's search time (:attr:`Result.runtime_s`); None on failure.
        worker_time_s: wall time of the whole job inside the worker: loading
            the robot, the travel-time matrix and the search.
        seed: the solver seed used.
        worker: ``host:pid`` of the process that ran the job (empty if it never ran).
    """

    id: str
    success: bool
    error: str | None = None
    total_time: float | None = None
    order: tuple[int, ...] | None = None
    runtime_s: float | None = None
    worker_time_s: float = 0.0
    seed: int = 0
    worker: str = ""

    def __post_init__(self) -> None:
        if self.success:
            if self.order is None or self.total_time is None or self.runtime_s is None:
                raise ParameterError(
                    f"JobResult {self.id!r}: a success needs order, total_time and runtime_s")
            if self.error is not None:
                raise ParameterError(f"JobResult {self.id!r}: a success has no error, "
                                     f"got {self.error!r}")
        elif not self.error:
            raise ParameterError(f"JobResult {self.id!r}: a failure needs an error message")
        if not math.isfinite(self.worker_time_s) or self.worker_time_s < 0:
            raise ParameterError(f"JobResult.worker_time_s must be >= 0, "
                                 f"got {self.worker_time_s!r}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (one entry of the ``batch`` command's ``--json``)."""
        return {"id": self.id, "success": self.success, "error": self.error,
                "total_time": self.total_time,
                "order": None if self.order is None else list(self.order),
                "runtime_s": self.runtime_s, "worker_time_s": self.worker_time_s,
                "seed": self.seed, "worker": self.worker}


@dataclass(frozen=True)
class _Task:
    """What travels to a worker: a job (its subtasks read already) or a pickled problem."""

    id: str
    seed: int
    job: Job | None = None
    subtasks: Any = None  # the job's targets, read on the calling machine
    problem: bytes | None = None
    warm_kind: tuple[str, str] = ("custom", "fixed")


def _pickle_problem(problem: PlanarProblem | MatrixProblem) -> bytes:
    """The problem as bytes a worker can load."""
    return pickle.dumps(problem, protocol=pickle.HIGHEST_PROTOCOL)


def _worker_name() -> str:
    from subtask_opt.batch.pool import worker_pid

    return f"{socket.gethostname()}:{worker_pid()}"


def _error_text(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _run_task(task: _Task, *, stop: Any, params: SolverParams | None) -> JobResult:
    """Solve one task in a worker; every exception becomes a failed JobResult."""
    from subtask_opt.arm.tasks import builtin_case
    from subtask_opt.kinematics.planar import load_planar_arm

    start = time.perf_counter()
    try:
        problem = None if task.problem is None else pickle.loads(task.problem)
        if problem is None and task.job is not None and task.job.serial:
            result = _solve_serial_job(task.job, task.subtasks, task.seed, stop, params)
        elif problem is None:
            job = task.job
            assert job is not None
            arm = load_planar_arm(job.robot)
            subtasks = (task.subtasks if task.subtasks is not None
                        else builtin_case(str(job.case), arm, seed=job.case_seed))
            problem = PlanarProblem(subtasks, arm, time_model=job.time_model,
                                    first=job.first, k=job.k, elbow=job.elbow,
                                    configurations=job.configuration_mode,
                                    line_fallback=job.line_fallback)
            constraints = (None if job.home is None
                           else TourConstraints(home=(job.home[0], job.home[1])))
            result = solve(problem, seed=task.seed, stop=stop, params=params,
                           constraints=constraints)
        else:
            result = solve(problem, seed=task.seed, stop=stop, params=params)
    except Exception as exc:  # one bad job must not stop the batch
        return JobResult(task.id, False, error=_error_text(exc), seed=task.seed,
                         worker_time_s=time.perf_counter() - start, worker=_worker_name())
    return JobResult(task.id, True, total_time=float(result.total_time),
                     order=tuple(int(i) for i in result.order), runtime_s=result.runtime_s,
                     worker_time_s=time.perf_counter() - start, seed=task.seed,
                     worker=_worker_name())


def _solve_serial_job(job: Job, targets: Any, seed: int, stop: Any,
                      params: SolverParams | None) -> Any:
    """A serial arm's job, solved as ``subtask-opt solve --robot ...`` solves it."""
    from subtask_opt.arm.problem import ArmProblem, load_robot
    from subtask_opt.arm.problem import solve as solve_arm

    robot = load_robot(job.robot, tool_frame=job.tool_frame)
    home = None if job.home is None else np.radians(np.asarray(job.home, dtype=float))
    problem = ArmProblem(targets, robot, home=home, scene=job.scene, detours=job.detours)
    return solve_arm(problem, seed=seed, stop=stop, params=params)


SERIAL_WARM_TARGETS = "x,y,z,dx,dy,dz\n0.45,-0.15,0.20,1,0,-0.3\n0.45,0.05,0.20,1,0,-0.3\n" \
                      "0.42,-0.10,0.35,1,0,-0.3\n"
"""Three UR5 holes: the warm-up of a batch with serial arms."""

_WARMED: set[tuple[tuple[str, str], ...]] = set()
WARM_SUBTASKS = 20
"""Subtasks of the warm-up problems: with 5, some operators that larger jobs call were left
for the first job to compile (29 s, in every worker), measured by benchmarks/cold_batch.py."""


def warm_up(kinds: tuple[tuple[str, str], ...] = (("trapezoid", "fixed"),)) -> None:
    """Load (or compile) the kernels a batch needs by solving tiny problems, once per process.

    Args:
        kinds: ``(time_model, configurations)`` pairs; ``("custom", "fixed")``
            warms the solver alone (problems from a matrix).
    """
    if kinds in _WARMED:
        return
    from subtask_opt._kernel_cache import announce_if_empty

    announce_if_empty("the kernels this batch needs")
    from subtask_opt.arm.tasks import random_subtasks
    from subtask_opt.base.stop import MaxGenerations
    from subtask_opt.kinematics.planar import load_planar_arm

    arm = load_planar_arm("planar_2r")
    subtasks = random_subtasks(arm, WARM_SUBTASKS, seed=0)
    for time_model, mode in kinds:
        try:
            if time_model == "serial":
                _warm_serial()
                continue
            if time_model == "custom":
                problem: PlanarProblem | MatrixProblem = MatrixProblem(
                    PlanarProblem(subtasks, arm, time_model="trapezoid").matrix)
            else:
                problem = PlanarProblem(subtasks, arm, time_model=time_model,
                                        configurations=mode)
            solve(problem, seed=0, stop=MaxGenerations(3))
        except SubtaskOptError as exc:  # e.g. a mode the model refuses: its jobs will say so
            warnings.warn(f"warm-up of the {time_model} model ({mode}) skipped: {exc}",
                          stacklevel=2)
    _WARMED.add(kinds)


def _warm_serial() -> None:
    """Compile or load a serial arm's kernels (IK, leg times, the clustered search)."""
    import tempfile

    from subtask_opt.arm.problem import ArmProblem, load_robot, load_targets
    from subtask_opt.arm.problem import solve as solve_arm
    from subtask_opt.base.stop import MaxGenerations

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "warm.csv"
        path.write_text(SERIAL_WARM_TARGETS)
        problem = ArmProblem(load_targets(path), load_robot("ur5"),
                             home=np.radians([0, -90, 90, -90, -90, 0]))
    solve_arm(problem, seed=0, stop=MaxGenerations(3))


def _warm_kinds(tasks: list[_Task]) -> tuple[tuple[str, str], ...]:
    kinds: set[tuple[str, str]] = set()
    for task in tasks:
        if task.job is not None and task.job.serial:
            kinds.add(("serial", "optimize"))
        elif task.job is not None:
            kinds.add((task.job.time_model, task.job.configuration_mode))
        else:
            kinds.add(task.warm_kind)
    return tuple(sorted(kinds))


def _seed_list(seeds: int | Sequence[int] | None, n: int) -> list[int | None]:
    if seeds is None:
        return [None] * n
    if isinstance(seeds, (int, np.integer)):
        require_int("solve_many", "seeds", seeds, 0, SEED_MAX)
        return [int(seeds)] * n
    if isinstance(seeds, (str, bytes)) or not isinstance(seeds, Iterable):
        raise ParameterError(f"solve_many.seeds must be an integer, a sequence of {n} integers "
                             f"or None, got {seeds!r}")
    values = list(seeds)
    if len(values) != n:
        raise ParameterError(
            f"solve_many.seeds must hold one seed per problem ({n}), got {len(values)}")
    for i, s in enumerate(values):
        require_int("solve_many", f"seeds[{i}]", s, 0, SEED_MAX)
    return [int(s) for s in values]


def _prepare(problems: Sequence[Job | PlanarProblem | MatrixProblem],
             seeds: int | Sequence[int] | None) -> tuple[list[_Task], dict[int, JobResult]]:
    """Tasks for the workers, and the jobs that failed already (unreadable subtask files)."""
    seed_of = _seed_list(seeds, len(problems))
    tasks: list[_Task] = []
    failed: dict[int, JobResult] = {}
    seen: dict[str, int] = {}
    for i, (item, seed) in enumerate(zip(problems, seed_of, strict=True)):
        if isinstance(item, Job):
            ident = item.id
            seed = item.seed if seed is None else seed
        elif isinstance(item, (PlanarProblem, MatrixProblem)):
            ident = f"problem-{i}"
            if seed is None:
                raise ParameterError(
                    f"solve_many: item {i} is a {type(item).__name__}, which has no seed of its "
                    "own: pass seeds= (one integer or one per item)")
        else:
            raise ParameterError(f"solve_many: item {i} must be a Job, PlanarProblem or "
                                 f"MatrixProblem, got {type(item).__name__}")
        if ident in seen:
            raise ParameterError(
                f"solve_many: job id {ident!r} is used twice (items {seen[ident]} and {i})")
        seen[ident] = i
        if isinstance(item, (PlanarProblem, MatrixProblem)):
            kind = (("custom", "fixed") if isinstance(item, MatrixProblem)
                    else (item.time_model, str(item.configurations)))
            tasks.append(_Task(ident, seed, problem=_pickle_problem(item), warm_kind=kind))
            continue
        job = replace(item, seed=seed) if seed != item.seed else item
        subtasks = None
        if not job.builtin:
            try:
                subtasks = (load_targets(job.case, standoff=job.standoff,
                                         axis_step=job.axis_step)
                            if job.serial else load_subtasks(job.case))
            except SubtaskOptError as exc:
                failed[i] = JobResult(ident, False, error=_error_text(exc), seed=seed)
        tasks.append(_Task(ident, seed, job=job, subtasks=subtasks))
    return tasks, failed


def solve_many(problems: Sequence[Job | PlanarProblem | MatrixProblem], *,
               seeds: int | Sequence[int] | None,
               stop: StoppingCriterion | list[StoppingCriterion] | None = None,
               client: Any = None, workers: int | None = None, progress: bool = False,
               params: SolverParams | None = None,
               on_result: Callable[[JobResult], None] | None = None,
               job_time_limit: float | None = None,
               isolate: bool = True) -> list[JobResult]:
    """Solve many sequencing jobs in parallel; one :class:`JobResult` per item, in input order.

    Each item is solved exactly as :func:`subtask_opt.solve` would solve it on
    its own with the same seed, so the results do not depend on where they ran
    (serially, on a process pool or on a cluster: bit-identical orders and times).

    Args:
        problems: :class:`Job` descriptions and/or ready problems
            (:class:`~subtask_opt.PlanarProblem`, ``MatrixProblem``).
        seeds: one seed for every item, a sequence of one seed per item, or
            None to use each Job's own ``seed`` (a ready problem then
            raises: it has no seed of its own).
        stop: stopping criteria of every job (default: the solver's).
        client: an existing dask.distributed cluster: a scheduler address
            ``"tcp://host:port"`` or a ``distributed.Client``. Needs
            ``pip install subtask_opt[cluster]``.
        workers: without ``client``: ``0`` solves here one after another;
            ``N`` runs N local worker processes (a Dask LocalCluster, or a
            process pool when dask is not installed); default: the machine's
            cores.
        progress: a progress bar of finished jobs (only on a terminal).
        params: solver parameters of every job.
        on_result: called with each JobResult as soon as it finishes
            (completion order; jobs whose file could not be read come first).
        job_time_limit: seconds one job may run (its whole job: reading, building,
            search) before it is stopped and fails with its reason; None: no limit.
            At most :data:`~subtask_opt.batch.pool.MAX_TIMEOUT_S`.
        isolate: run each job in its own process forked from its worker (POSIX), so a
            job that crashes (a signal, running out of memory) or is stopped by
            ``job_time_limit`` fails alone and every other job keeps its answer.

    The kernels are loaded (or compiled, once, with a notice on stderr) in this process
    before any local worker starts, so the workers only load them from the cache; then
    every worker loads them before its first job by solving a tiny problem of each
    time model in the batch.

    Raises:
        ParameterError: a bad item, seed, duplicate id, or cluster option;
            a scheduler address without dask installed. A job that fails
            does not raise: its JobResult says why.
    """
    if isinstance(problems, (Job, PlanarProblem, MatrixProblem)):
        problems = [problems]
    if isinstance(problems, (str, bytes, dict)) or not isinstance(problems, Iterable):
        raise ParameterError(f"solve_many.problems must be a list of Jobs or problems, got "
                             f"{type(problems).__name__}")
    problems = list(problems)
    if stop is not None:
        from subtask_opt.base.stop import as_criteria

        stop = as_criteria(stop, [])
    if params is not None and not isinstance(params, SolverParams):
        raise ParameterError(f"solve_many.params must be SolverParams, got {params!r}")
    if job_time_limit is not None:
        from subtask_opt.batch.pool import MAX_TIMEOUT_S

        require_in_range("solve_many", "job_time_limit", job_time_limit, 0.0, MAX_TIMEOUT_S)
        if job_time_limit <= 0:
            raise ParameterError(f"solve_many.job_time_limit must be > 0, got "
                                 f"{job_time_limit!r}")
        isolate = True
    tasks, failed = _prepare(problems, seeds)
    results: list[JobResult | None] = [failed.get(i) for i in range(len(tasks))]
    for r in failed.values():
        if on_result is not None:
            on_result(r)
    todo = [i for i in range(len(tasks)) if i not in failed]
    run = partial(_run_task, stop=stop, params=params)

    def finished(k: int, value: Any) -> None:
        task = tasks[todo[k]]
        if isinstance(value, BaseException):  # the machinery failed, e.g. workers kept dying
            value = JobResult(task.id, False, error=_error_text(value), seed=task.seed)
        results[todo[k]] = value
        if on_result is not None:
            on_result(value)

    if todo:
        warm = partial(warm_up, _warm_kinds([tasks[i] for i in todo]))
        if client is None and (workers != 0 or isolate):
            # compile once here, with the notice: worker processes then load the cache, and
            # jobs forked from this process (isolate) inherit the compiled kernels
            warm()
        map_jobs(run, [tasks[i] for i in todo], workers=workers, scheduler=client,
                 warm_up=warm, on_result=finished, return_exceptions=True,
                 progress=progress, desc="batch", isolate=isolate,
                 timeout=job_time_limit)
    assert all(r is not None for r in results)
    return results  # type: ignore[return-value]


def overhead_per_job(results: Sequence[JobResult], wall_s: float, slots: int) -> float:
    """Seconds the batch machinery added per job: ``(wall_s * slots - sum(worker_time_s)) / jobs``.

    ``slots`` is the number of workers that ran jobs in parallel; with one
    worker this is the batch's wall time minus the jobs' own times, per job.
    """
    require_int("overhead_per_job", "slots", slots, 1)
    if not results:
        raise ParameterError("overhead_per_job needs at least one result")
    return (wall_s * slots - sum(r.worker_time_s for r in results)) / len(results)


def load_jobs(paths: Sequence[str | Path], **file_options: Any) -> list[Job]:
    """Jobs from subtask files and JSON manifests (the ``batch`` command's JOBS).

    A ``.csv`` file, or a ``.json`` object with ``"points"``, is one job whose
    id is the path as given. A manifest is a ``.json`` list of jobs or an object
    ``{"jobs": [...]}``; each job an object with ``id``, ``case`` (a built-in
    name or a subtask file, relative to the manifest) and optionally the other
    :class:`Job` fields (``robot``, ``time_model``, ``seed``, ...).

    A subtask file's content is checked when its job runs (a bad one fails that
    job only); a path that does not exist, or a malformed manifest, raises.
    ``file_options`` (``robot``, ``scene``, ``home``, ...: :class:`Job` fields) apply to
    the jobs of subtask and target files; a manifest gives each job its own, so it may
    not be mixed with them.

    Raises:
        InputDataError: a missing file, a file neither subtasks nor manifest,
            a malformed manifest entry (its index and key named).
    """
    jobs: list[Job] = []
    for raw in paths:
        path = Path(raw)
        suffix = path.suffix.lower()
        # a regular file, never a FIFO or a device; a subtask file's size is its job's to
        # refuse (that job fails, the others run), a manifest's is the batch's
        check_input_file(path, "job file",
                         **({"max_bytes": sys.maxsize} if suffix == ".csv" else {}))
        if suffix == ".csv":
            jobs.append(_file_job(raw, file_options))
            continue
        if suffix != ".json":
            raise InputDataError(f"job file must be a .csv or .json subtask file or a .json "
                                 f"manifest, got {path.name!r}")
        data = parse_json(read_text(path, "job file"), str(raw))
        if isinstance(data, dict) and ("points" in data or "targets" in data):
            jobs.append(_file_job(raw, file_options))
            continue
        if file_options:
            name = next(iter(file_options))
            flag = "--no-detours" if name == "detours" else f"--{name.replace('_', '-')}"
            raise ParameterError(f"{flag} applies to "
                                 f"subtask and target files; the manifest {raw} gives each "
                                 "job its own")
        entries = data.get("jobs") if isinstance(data, dict) else data
        if not isinstance(entries, list) or not entries:
            raise InputDataError(f'{raw}: expected a subtask file {{"points": ...}} or a '
                                 f'manifest {{"jobs": [{{"id": ..., "case": ...}}, ...]}}')
        jobs.extend(Job.from_dict(e, base_dir=path.parent, where=f"{raw}, job {i}")
                    for i, e in enumerate(entries))
    seen: set[str] = set()
    for job in jobs:
        if job.id in seen:
            raise InputDataError(f"job id {job.id!r} appears twice")
        seen.add(job.id)
    return jobs


def _file_job(raw: str | Path, options: dict[str, Any]) -> Job:
    try:
        return Job(str(raw), str(raw), **options)
    except ParameterError as exc:
        raise ParameterError(f"{raw}: {exc}") from None


__all__ = ["Job", "JobResult", "load_jobs", "overhead_per_job", "solve_many", "warm_up"]
