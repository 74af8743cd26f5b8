"""Concurrency and faults (issue 30, item 2).

* the same problem solved from 8 threads gives the solo answer;
* two processes compiling into one empty kernel cache both succeed, and a third then
  loads every kernel from it (no compile notice, the same answer);
* a read-only or full cache folder still solves, after one warning line;
* a batch with a job that crashes its process, one that hangs past the per-job limit and
  one with bad input among good jobs reports every job, keeps every good answer (equal to
  the job solved alone) and the CLI exits 1.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from subtask_opt import solve
from subtask_opt.arm.planar_problem import PlanarProblem
from subtask_opt.arm.tasks import builtin_case, random_subtasks, save_subtasks
from subtask_opt.base.errors import ParameterError
from subtask_opt.base.stop import MaxGenerations, NoImprovement
from subtask_opt.batch import Job, map_jobs, solve_many
from subtask_opt.batch.pool import JobCrashed, JobTimeout
from subtask_opt.cli.app import main
from subtask_opt.kinematics.planar import load_planar_arm
from subtask_opt.tour.problem import MatrixProblem

ROOT = Path(__file__).resolve().parents[1]
GRID = [sys.executable, "-m", "subtask_opt.cli", "plan", "grid", "--map", "open",
        "--planner", "dt"]


@pytest.fixture(scope="module")
def arm():
    return load_planar_arm("planar_2r")


# ----------------------------------------------------------------------- 8 threads

@pytest.mark.parametrize("kind", ["planar", "matrix"])
def test_eight_threads_give_the_solo_answer(arm, kind):
    subtasks = builtin_case("square20", arm)
    problem: PlanarProblem | MatrixProblem = PlanarProblem(subtasks, arm)
    if kind == "matrix":
        problem = MatrixProblem(PlanarProblem(subtasks, arm, time_model="trapezoid").matrix)
    stop = MaxGenerations(60)
    solo = [solve(problem, seed=s, stop=stop) for s in range(8)]
    with ThreadPoolExecutor(8) as pool:
        threaded = list(pool.map(lambda s: solve(problem, seed=s, stop=stop), range(8)))
    for s, (a, b) in enumerate(zip(solo, threaded, strict=True)):
        assert list(a.order) == list(b.order), s
        assert a.total_time == b.total_time, s
    # the seeds do differ: the check above compares different answers, not one answer 8x
    assert len({tuple(r.order) for r in solo}) > 1


# ------------------------------------------------------------------ the kernel cache

def _env(cache: Path) -> dict[str, str]:
    env = dict(os.environ, SUBTASK_OPT_CACHE_DIR=str(cache), PYTHONPATH=str(ROOT))
    env.pop("NUMBA_DISABLE_JIT", None)
    return env


def _answer(stdout: str) -> str:
    """The planner's printed answer without its run time."""
    return re.sub(r", [0-9.]+ ms", "", stdout)


def test_two_processes_compiling_into_one_empty_cache(tmp_path):
    cache = tmp_path / "cache"
    procs = [subprocess.Popen(GRID, env=_env(cache), stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, cwd=tmp_path)
             for _ in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], outs
    assert _answer(outs[0][0]) == _answer(outs[1][0])
    index = list(cache.rglob("*.nbi"))
    assert index, "nothing was cached"
    third = subprocess.run(GRID, env=_env(cache), capture_output=True, text=True,
                           cwd=tmp_path, timeout=600)
    assert third.returncode == 0, third.stderr
    assert "compiling" not in third.stderr  # every kernel loaded from the shared cache
    assert _answer(third.stdout) == _answer(outs[0][0])


def _mount(path: Path, options: str) -> bool:
    path.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)],
                          capture_output=True, check=False)
    return done.returncode == 0


@pytest.mark.parametrize("kind", ["read-only", "full", "below a file"])
def test_an_unusable_cache_folder_still_solves_with_one_warning(tmp_path, kind):
    cache = tmp_path / "cache"
    mounted = False
    if kind == "below a file":
        (tmp_path / "file").write_text("x")
        cache = tmp_path / "file" / "cache"
    else:
        mounted = _mount(cache, "size=64k,ro" if kind == "read-only" else "size=64k")
        if not mounted:
            pytest.skip("cannot mount a tmpfs here")
        if kind == "full":
            with open(cache / "filler", "wb") as fh, pytest.raises(OSError):
                fh.write(b"\0" * (1 << 20))
    try:
        done = subprocess.run(GRID, env=_env(cache), capture_output=True, text=True,
                              cwd=tmp_path, timeout=600)
    finally:
        if mounted:
            subprocess.run(["umount", str(cache)], check=False)
    assert done.returncode == 0, done.stderr
    assert "length" in done.stdout
    warnings = [ln for ln in done.stderr.splitlines() if "warning" in ln]
    assert len(warnings) == 1, done.stderr
    assert str(cache) in warnings[0] and "compiling in memory" in warnings[0]
    assert "Traceback" not in done.stderr
    # numba did not fall back to __pycache__ beside the sources
    assert not list((ROOT / "subtask_opt").rglob("*.nbi"))


# ------------------------------------------------------------------- batch faults

class _Crashes(MatrixProblem):
    """A problem whose unpickling in the worker kills that process (SIGABRT)."""

    def __reduce__(self):  # type: ignore[override]
        return (os.abort, ())


class _Hangs(MatrixProblem):
    """A problem whose unpickling in the worker sleeps for an hour."""

    def __reduce__(self):  # type: ignore[override]
        return (time.sleep, (3600,))


def _crash(x: int) -> int:
    if x == 3:
        os.abort()
    if x == 5:
        time.sleep(3600)
    return x * x


@pytest.mark.parametrize("workers", [0, 2])
def test_map_jobs_isolates_a_crash_and_stops_a_hang(workers):
    out = map_jobs(_crash, range(8), workers=workers, isolate=True, timeout=5.0,
                   return_exceptions=True)
    for x, value in enumerate(out):
        if x == 3:
            assert isinstance(value, JobCrashed) and "SIGABRT" in str(value)
        elif x == 5:
            assert isinstance(value, JobTimeout) and "5 s" in str(value)
        else:
            assert value == x * x


def test_map_jobs_timeout_needs_isolation_and_a_sane_value():
    for bad in (0, -1, float("nan"), 1e30):
        with pytest.raises(ParameterError):
            map_jobs(abs, [1], isolate=True, timeout=bad)
    with pytest.raises(ParameterError, match="isolate"):
        map_jobs(abs, [1], timeout=1.0)


@pytest.mark.parametrize("workers", [0, 2])
def test_solve_many_reports_crashing_hanging_and_bad_jobs_and_keeps_the_good(
        arm, tmp_path, workers, monkeypatch):
    if workers:  # the process pool: the test's problem classes import in its workers
        monkeypatch.setattr("subtask_opt.batch.pool.dask_available", lambda: False)
    matrix = PlanarProblem(random_subtasks(arm, 6, seed=1), arm, time_model="trapezoid").matrix
    good = [Job(f"good{i}", "square20", seed=i) for i in range(3)]
    bad_file = tmp_path / "bad.csv"
    bad_file.write_text("x,y\n1e999,0\n")
    items = [good[0], _Crashes(matrix), good[1], _Hangs(matrix),
             Job("bad-input", str(bad_file)), good[2], MatrixProblem(matrix)]
    stop = MaxGenerations(20)
    results = solve_many(items, seeds=[0, 0, 1, 0, 0, 2, 4], stop=stop, workers=workers,
                         job_time_limit=20.0)
    assert [r.id for r in results] == ["good0", "problem-1", "good1", "problem-3",
                                       "bad-input", "good2", "problem-6"]
    ok = {r.id: r for r in results if r.success}
    assert set(ok) == {"good0", "good1", "good2", "problem-6"}
    crashed, hung, bad = results[1], results[3], results[4]
    assert "JobCrashed" in crashed.error and "SIGABRT" in crashed.error
    assert "JobTimeout" in hung.error and "20 s" in hung.error
    assert "InputDataError" in bad.error
    for i, job in enumerate(good):  # every good answer is the job solved alone
        alone = solve(PlanarProblem(builtin_case("square20", arm), arm), seed=i, stop=stop)
        assert list(ok[job.id].order) == list(alone.order)
        assert ok[job.id].total_time == alone.total_time
    alone = solve(MatrixProblem(matrix), seed=4, stop=stop)
    assert list(ok["problem-6"].order) == list(alone.order)


def test_batch_cli_with_a_slow_and_a_bad_job_reports_all_and_exits_1(arm, tmp_path, capsys):
    for i in range(2):
        save_subtasks(random_subtasks(arm, 6, seed=i), tmp_path / f"good{i}.csv")
    (tmp_path / "bad.csv").write_text("x,y\n0.3,\u0663\n")
    # 1,500 reachable subtasks: the search alone runs for minutes, the limit stops it
    radii, angles = np.linspace(0.3, 0.55, 30), np.linspace(-1.5, 1.5, 50)
    (tmp_path / "slow.csv").write_text("x,y\n" + "".join(
        f"{r * math.cos(a)!r},{r * math.sin(a)!r}\n" for r in radii.tolist()
        for a in angles.tolist()))
    out = tmp_path / "out.json"
    argv = ["batch", *(str(tmp_path / f) for f in ("good0.csv", "slow.csv", "bad.csv",
                                                  "good1.csv")),
            "--workers", "0", "--no-improvement", "50", "--job-time-limit", "5",
            "--no-progress", "--json", str(out)]
    code = main(argv)
    text = capsys.readouterr().out
    assert code == 1
    report = json.loads(out.read_text())
    jobs = {Path(j["id"]).name: j for j in report["jobs"]}
    assert set(jobs) == {"good0.csv", "slow.csv", "bad.csv", "good1.csv"}
    assert jobs["good0.csv"]["success"] and jobs["good1.csv"]["success"]
    assert "JobTimeout" in jobs["slow.csv"]["error"]
    assert "InputDataError" in jobs["bad.csv"]["error"]
    assert report["summary"]["failed"] == 2 and "2 failed" in text
    for i in range(2):
        alone = solve(PlanarProblem(random_subtasks(arm, 6, seed=i), arm), seed=0,
                      stop=NoImprovement(50))
        assert jobs[f"good{i}.csv"]["order"] == [int(v) for v in np.asarray(alone.order)]
