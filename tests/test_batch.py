"""Batches: solve_many gives the same answers serially, on Dask and on a process pool.

The oracle of every batch is the plain :func:`subtask_opt.solve` of each job on
its own, with the same seed: a batch must reproduce it bit for bit wherever the
job ran, report a bad job's error without losing the others, and survive a
worker killed mid-batch.
"""

from __future__ import annotations

import json
import os
import signal
import sys

import numpy as np
import pytest

from subtask_opt import solve
from subtask_opt.arm.planar_problem import PlanarProblem
from subtask_opt.arm.tasks import builtin_case, load_subtasks, random_subtasks, save_subtasks
from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.base.stop import MaxGenerations, NoImprovement
from subtask_opt.batch import (
    INSTALL_HINT,
    Job,
    JobResult,
    load_jobs,
    map_jobs,
    overhead_per_job,
    solve_many,
)
from subtask_opt.batch.pool import chunk_size, dask_available, job_indices
from subtask_opt.kinematics.planar import load_planar_arm
from subtask_opt.tour.problem import MatrixProblem

STOP = [NoImprovement(10), MaxGenerations(400)]
N_JOBS = 50
BAD = 17  # the job whose subtasks the arm cannot reach


@pytest.fixture(scope="module")
def arm():
    return load_planar_arm("planar_2r")


@pytest.fixture(scope="module")
def batch(arm, tmp_path_factory):
    """50 tiny jobs: subtask files, built-in cases, ready problems, one matrix problem,
    and one job (index BAD) with a subtask out of the arm's reach."""
    folder = tmp_path_factory.mktemp("parts")
    items: list = []
    for i in range(N_JOBS):
        sub = random_subtasks(arm, 5 + i % 5, seed=100 + i)
        if i == BAD:
            far = np.vstack([sub.points, [[5.0 * arm.r_max, 0.0]]])
            path = folder / f"part{i}.csv"
            path.write_text("x,y\n" + "".join(f"{float(x)!r},{float(y)!r}\n" for x, y in far))
            items.append(Job(f"part{i}", str(path), time_model="trapezoid"))
        elif i % 5 == 0:
            items.append(PlanarProblem(sub, arm, time_model="trapezoid"))
        elif i == 49:
            items.append(MatrixProblem(PlanarProblem(sub, arm, time_model="trapezoid").matrix))
        elif i % 5 == 1:
            path = folder / f"part{i}.json"
            save_subtasks(sub, path)
            items.append(Job(f"part{i}", str(path), time_model="joint", seed=3))
        else:
            path = folder / f"part{i}.csv"
            save_subtasks(sub, path)
            items.append(Job(f"part{i}", str(path), time_model="trapezoid"))
    seeds = [i % 7 for i in range(N_JOBS)]
    return items, seeds


def _problem_of(item, arm):
    if not isinstance(item, Job):
        return item
    subtasks = load_subtasks(item.case) if not item.builtin else builtin_case(item.case, arm)
    return PlanarProblem(subtasks, arm, time_model=item.time_model)


@pytest.fixture(scope="module")
def expected(batch, arm):
    """Each job solved on its own by solve(), the oracle of every batch."""
    items, seeds = batch
    out = {}
    for i, (item, seed) in enumerate(zip(items, seeds, strict=True)):
        if i == BAD:
            continue
        r = solve(_problem_of(item, arm), seed=seed, stop=STOP)
        out[i] = (tuple(int(v) for v in r.order), r.total_time)
    return out


@pytest.fixture(scope="module")
def serial(batch):
    items, seeds = batch
    return solve_many(items, seeds=seeds, stop=STOP, workers=0)


def _answers(results):
    return [(r.id, r.success, r.order, r.total_time, r.seed, r.error) for r in results]


def _check_batch(results, batch, expected):
    items, seeds = batch
    assert len(results) == N_JOBS
    for i, r in enumerate(results):
        want_id = items[i].id if isinstance(items[i], Job) else f"problem-{i}"
        assert r.id == want_id and r.seed == seeds[i]
        if i == BAD:
            assert not r.success and r.order is None and r.total_time is None
            assert r.error.startswith("UnreachableError: "), r.error
        else:
            assert r.success, r.error
            assert (r.order, r.total_time) == expected[i]
            assert r.worker_time_s >= r.runtime_s > 0


def test_serial_batch_reproduces_each_solve(serial, batch, expected):
    _check_batch(serial, batch, expected)
    assert {r.worker for r in serial} == {f"{os.uname().nodename}:{os.getpid()}"}


@pytest.fixture(scope="module")
def client():
    """A real local cluster: two worker processes of one thread each (closed after the module).

    (``workers=2`` builds the same cluster inside solve_many; tests/cli/test_batch.py runs it.)
    """
    if not dask_available():
        pytest.skip("needs subtask_opt[cluster]")
    import logging

    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=":0", silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as client:
        yield client


def test_local_dask_cluster_gives_bit_identical_results(serial, batch, expected, client):
    items, seeds = batch
    streamed = []
    results = solve_many(items, seeds=seeds, stop=STOP, client=client, on_result=streamed.append)
    _check_batch(results, batch, expected)
    assert _answers(results) == _answers(serial)
    assert sorted(r.id for r in streamed) == sorted(r.id for r in results)
    pids = {int(r.worker.rsplit(":", 1)[1]) for r in results}
    assert os.getpid() not in pids and 1 <= len(pids) <= 2


def test_process_pool_fallback_without_dask_gives_bit_identical_results(
        serial, batch, expected, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # `import distributed` now fails
    items, seeds = batch
    results = solve_many(items, seeds=seeds, stop=STOP, workers=2)
    _check_batch(results, batch, expected)
    assert _answers(results) == _answers(serial)
    assert os.getpid() not in {int(r.worker.rsplit(":", 1)[1]) for r in results}


def test_scheduler_address_without_dask_says_what_to_install(batch, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    items, seeds = batch
    with pytest.raises(ParameterError, match=r"pip install subtask_opt\[cluster\]") as info:
        solve_many(items[:2], seeds=seeds[:2], client="tcp://127.0.0.1:8786")
    assert "\n" not in str(info.value) and INSTALL_HINT in str(info.value)


def test_killed_worker_jobs_are_rerun_and_the_batch_completes(arm, client):
    import psutil

    problems = [PlanarProblem(random_subtasks(arm, 16, seed=500 + i), arm,
                              time_model="trapezoid") for i in range(N_JOBS)]
    seeds = list(range(N_JOBS))
    stop = [NoImprovement(30), MaxGenerations(2000)]
    want = [solve(p, seed=s, stop=stop) for p, s in zip(problems, seeds, strict=True)]
    killed: dict = {}

    def kill_a_busy_worker(result: JobResult) -> None:
        if killed:
            return
        for address, keys in client.processing().items():
            if keys:
                killed["pid"] = client.run(os.getpid, workers=[address])[address]
                killed["jobs"] = set().union(*(job_indices(k) for k in keys))
                os.kill(killed["pid"], signal.SIGKILL)
                return

    results = solve_many(problems, seeds=seeds, stop=stop, client=client,
                         on_result=kill_a_busy_worker)
    assert killed, "no worker was busy: the kill never happened"
    assert killed["jobs"]
    assert not psutil.pid_exists(killed["pid"]) or (
        psutil.Process(killed["pid"]).status() == psutil.STATUS_ZOMBIE)  # dead, maybe unreaped
    assert [r.success for r in results] == [True] * N_JOBS
    assert [(r.order, r.total_time) for r in results] == [
        (tuple(int(v) for v in w.order), w.total_time) for w in want]
    for i in killed["jobs"]:  # the victim's jobs ran again, elsewhere
        assert not results[i].worker.endswith(f":{killed['pid']}")


def test_a_job_whose_file_cannot_be_read_fails_alone(tmp_path, arm):
    good = tmp_path / "good.csv"
    save_subtasks(random_subtasks(arm, 6, seed=1), good)
    dup = tmp_path / "dup.csv"
    dup.write_text("x,y\n0.3,0.1\n0.3,0.1\n0.25,0.3\n")
    jobs = [Job("good", str(good)), Job("missing", str(tmp_path / "nope.csv")),
            Job("dup", str(dup)), Job("square", "square20", time_model="trapezoid")]
    results = solve_many(jobs, seeds=None, stop=STOP, workers=0)
    assert [r.success for r in results] == [True, False, False, True]
    assert "nope.csv" in results[1].error and results[1].error.startswith("InputDataError")
    assert "duplicate" in results[2].error
    want = solve(PlanarProblem(builtin_case("square20", arm), arm, time_model="trapezoid"),
                 seed=0, stop=STOP)
    assert results[3].total_time == want.total_time


def test_seeds_none_uses_each_jobs_seed_and_an_int_overrides_all(tmp_path, arm):
    path = tmp_path / "p.csv"
    sub = random_subtasks(arm, 9, seed=4)
    save_subtasks(sub, path)
    problem = PlanarProblem(sub, arm, time_model="trapezoid")
    jobs = [Job(f"s{s}", str(path), time_model="trapezoid", seed=s) for s in (1, 2)]
    own = solve_many(jobs, seeds=None, stop=[MaxGenerations(2)], workers=0)
    assert [r.seed for r in own] == [1, 2]
    assert [r.total_time for r in own] == [
        solve(problem, seed=s, stop=[MaxGenerations(2)]).total_time for s in (1, 2)]
    assert [r.seed for r in solve_many(jobs, seeds=9, stop=STOP, workers=0)] == [9, 9]


@pytest.mark.parametrize(("seeds", "needle"), [
    ([1], "one seed per problem"),
    ([0, -1], "seeds[1]"),
    (2**63, "seeds"),
    ("1", "seeds"),
    (None, "pass seeds="),
])
def test_bad_seeds_raise(arm, seeds, needle):
    problem = MatrixProblem(np.ones((3, 3)) - np.eye(3))
    with pytest.raises(ParameterError) as info:
        solve_many([Job("a", "square20"), problem], seeds=seeds, workers=0)
    assert needle in str(info.value)


def test_bad_batches_raise_before_running():
    with pytest.raises(ParameterError, match="used twice"):
        solve_many([Job("a", "square20"), Job("a", "random30")], seeds=0, workers=0)
    with pytest.raises(ParameterError, match="item 1 must be a Job"):
        solve_many([Job("a", "square20"), "square20"], seeds=0, workers=0)
    with pytest.raises(ParameterError, match="not both"):
        solve_many([Job("a", "square20")], seeds=0, workers=2, client="tcp://127.0.0.1:1")
    with pytest.raises(ParameterError, match="workers"):
        solve_many([Job("a", "square20")], seeds=0, workers=-1)
    with pytest.raises(ParameterError, match="address"):
        solve_many([Job("a", "square20")], seeds=0, client="127.0.0.1:8786")


@pytest.mark.parametrize(("field", "value"), [
    ("id", ""), ("id", 3), ("case", ""), ("case", 5), ("robot", ""), ("time_model", "magic"),
    ("seed", -1), ("seed", 2**63), ("seed", 1.5), ("case_seed", True), ("first", -2),
    ("k", 0.5), ("k", -0.1), ("elbow", 2), ("configurations", "best"),
    ("line_fallback", "skip"),
])
def test_job_rejects_bad_fields(field, value):
    kwargs = {"id": "a", "case": "square20", field: value}
    with pytest.raises(ParameterError) as info:
        Job(**kwargs)
    assert field in str(info.value) and repr(value) in str(info.value)


def test_job_result_must_be_consistent():
    with pytest.raises(ParameterError, match="needs order"):
        JobResult("a", True)
    with pytest.raises(ParameterError, match="error message"):
        JobResult("a", False)
    with pytest.raises(ParameterError, match="no error"):
        JobResult("a", True, error="x", order=(0, 1, 2), total_time=1.0, runtime_s=0.1)
    r = JobResult("a", True, order=(0, 2, 1), total_time=1.5, runtime_s=0.1, worker_time_s=0.2)
    assert json.loads(json.dumps(r.to_dict()))["order"] == [0, 2, 1]


def test_overhead_per_job_is_the_time_no_job_used():
    rs = [JobResult(str(i), True, order=(0, 1, 2), total_time=1.0, runtime_s=0.1,
                    worker_time_s=t) for i, t in enumerate((0.5, 1.0, 1.5))]
    assert overhead_per_job(rs, wall_s=3.3, slots=1) == pytest.approx(0.1)
    assert overhead_per_job(rs, wall_s=1.8, slots=2) == pytest.approx(0.2)
    with pytest.raises(ParameterError, match="slots"):
        overhead_per_job(rs, wall_s=1.0, slots=0)


def _square_or_raise(x: int) -> int:
    if x == 3:
        raise ValueError("three is bad")
    return x * x


def test_map_jobs_keeps_input_order_streams_and_returns_or_raises_exceptions():
    seen = []
    out = map_jobs(_square_or_raise, range(6), workers=0, return_exceptions=True,
                   on_result=lambda i, v: seen.append(i))
    assert out[:3] == [0, 1, 4] and out[4:] == [16, 25]
    assert isinstance(out[3], ValueError) and seen == list(range(6))
    with pytest.raises(ValueError, match="three"):
        map_jobs(_square_or_raise, range(6), workers=0)
    assert map_jobs(_square_or_raise, [], workers=0) == []


def test_load_jobs_reads_files_and_manifests(tmp_path, arm):
    parts = tmp_path / "parts"
    parts.mkdir()
    save_subtasks(random_subtasks(arm, 5, seed=0), parts / "a.csv")
    save_subtasks(random_subtasks(arm, 5, seed=1), parts / "b.json")
    manifest = tmp_path / "jobs.json"
    manifest.write_text(json.dumps({"jobs": [
        {"id": "m1", "case": "parts/a.csv", "robot": "asr_twodof", "time_model": "line",
         "seed": 4},
        {"id": "m2", "case": "random30", "case_seed": 7},
    ]}))
    jobs = load_jobs([str(parts / "a.csv"), str(parts / "b.json"), str(manifest)])
    assert [j.id for j in jobs] == [str(parts / "a.csv"), str(parts / "b.json"), "m1", "m2"]
    assert jobs[2].case == str(tmp_path / "parts" / "a.csv")
    assert (jobs[2].robot, jobs[2].time_model, jobs[2].seed) == ("asr_twodof", "line", 4)
    assert jobs[3].builtin and jobs[3].case_seed == 7


@pytest.mark.parametrize(("content", "needle"), [
    ('[{"id": "a", "case": "square20", "speed": 3}]', "'speed'"),
    ('[{"case": "square20"}]', "'id'"),
    ('[{"id": "a", "case": "square20", "seed": -4}]', "-4"),
    ('[{"id": "a", "case": "square20"}, {"id": "a", "case": "random30"}]', "twice"),
    ('{"jobs": []}', "manifest"),
    ('{"jobs": [1, 2]}', "job 0"),
    ("[{", "not valid JSON"),
])
def test_load_jobs_rejects_bad_manifests(tmp_path, content, needle):
    path = tmp_path / "m.json"
    path.write_text(content)
    with pytest.raises(InputDataError) as info:
        load_jobs([str(path)])
    assert needle in str(info.value) and "\n" not in str(info.value)


def test_load_jobs_rejects_missing_and_unknown_files(tmp_path):
    with pytest.raises(InputDataError, match="not found"):
        load_jobs([str(tmp_path / "nope.csv")])
    other = tmp_path / "a.txt"
    other.write_text("x")
    with pytest.raises(InputDataError, match="a.txt"):
        load_jobs([str(other)])


def test_a_job_with_an_impossible_mode_fails_alone_and_the_warm_up_says_why():
    from subtask_opt.batch import jobs as jobs_module

    jobs = [Job("bad-mode", "square20", time_model="trapezoid", configurations="optimize"),
            Job("fine", "square20", time_model="trapezoid")]
    jobs_module._WARMED.clear()
    with pytest.warns(UserWarning, match="warm-up of the trapezoid model"):
        results = solve_many(jobs, seeds=0, stop=STOP, workers=0)
    assert [r.success for r in results] == [False, True]
    assert results[0].error.startswith("ParameterError: ") and "joint or line" in results[0].error


def test_chunks_give_every_worker_four_tasks_and_keys_name_their_items():
    assert [chunk_size(n, slots) for n, slots in [(200, 2), (50, 2), (7, 2), (1000, 0)]] == [
        8, 6, 1, 8]
    assert job_indices("subtask_opt-jobs-0123abcd-6-12") == range(6, 12)
    assert job_indices("other-0123abcd-6-12") is None
    assert job_indices("subtask_opt-jobs-0123abcd-6") is None
