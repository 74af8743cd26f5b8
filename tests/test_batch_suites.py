"""The AGV and reactive suites on 1 process, 2 Dask workers and the process pool: same reports.

Each suite run depends on its seed only, so the report of a parallel run must
equal the serial one field for field (wall times aside). The oracle is the
plain serial loop of the planners (no mapper at all), not a stored run.
"""

from __future__ import annotations

import logging
import sys

import pytest

from subtask_opt.base.errors import ParameterError
from subtask_opt.batch import dask_available, suite_mapper, warm_agv, warm_reactive
from subtask_opt.batch.pool import INSTALL_HINT
from subtask_opt.cli import main
from subtask_opt.planners.agv.scenarios import run_agv_suite
from subtask_opt.planners.reactive.simulation import benchmark_navigators

AGV_RUNS = 10
REACTIVE_RUNS = 4


def _agv(report) -> dict:
    data = report.to_dict()
    data.pop("seconds")
    return data


def _reactive(table: dict) -> dict:
    return {name: {k: v for k, v in row.items() if k != "mean_runtime_s"}
            for name, row in table.items()}


@pytest.fixture(scope="module")
def client():
    """A real LocalCluster of two single-thread worker processes, closed after the module."""
    if not dask_available():
        pytest.skip("needs subtask_opt[cluster]")
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=":0", silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as client:
        yield client


@pytest.fixture(scope="module")
def agv_serial():
    return _agv(run_agv_suite(AGV_RUNS, 5))


@pytest.fixture(scope="module")
def reactive_serial():
    return _reactive(benchmark_navigators(REACTIVE_RUNS, 3))


def test_agv_suite_is_the_same_on_one_worker_here(agv_serial):
    report = run_agv_suite(AGV_RUNS, 5, map_runs=suite_mapper(workers=0, warm_up=warm_agv))
    assert _agv(report) == agv_serial


def test_agv_suite_is_the_same_on_two_dask_workers(agv_serial, client):
    report = run_agv_suite(AGV_RUNS, 5, map_runs=suite_mapper(scheduler=client,
                                                               warm_up=warm_agv))
    assert report.runs == AGV_RUNS
    assert _agv(report) == agv_serial


def test_agv_suite_is_the_same_on_the_process_pool(agv_serial, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # `import distributed` fails
    report = run_agv_suite(AGV_RUNS, 5, map_runs=suite_mapper(workers=2, warm_up=warm_agv))
    assert _agv(report) == agv_serial


def test_reactive_suite_is_the_same_on_two_dask_workers_and_the_pool(
        reactive_serial, client, monkeypatch):
    on_dask = benchmark_navigators(REACTIVE_RUNS, 3, map_runs=suite_mapper(
        scheduler=client, warm_up=warm_reactive))
    assert _reactive(on_dask) == reactive_serial
    monkeypatch.setitem(sys.modules, "distributed", None)
    on_pool = benchmark_navigators(REACTIVE_RUNS, 3, map_runs=suite_mapper(
        workers=2, warm_up=warm_reactive))
    assert _reactive(on_pool) == reactive_serial


def test_the_suite_mapper_keeps_the_order_of_its_items():
    assert suite_mapper(workers=0)(abs, [3, -1, -7, 2]) == [3, 1, 7, 2]


def test_a_scheduler_without_dask_is_refused_in_one_line(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(ParameterError, match=r"pip install subtask_opt\[cluster\]") as info:
        suite_mapper(scheduler="tcp://127.0.0.1:8786")(abs, [1, 2])
    assert "\n" not in str(info.value) and INSTALL_HINT in str(info.value)


@pytest.mark.parametrize("suite", ["agv", "reactive"])
def test_bench_scheduler_without_dask_exits_2_in_one_line(suite, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)
    code = main(["bench", suite, "--n", "2", "--scheduler", "tcp://127.0.0.1:8786",
                 "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and INSTALL_HINT in err and "Traceback" not in err


@pytest.mark.parametrize("argv", [["--workers", "-1"], ["--workers", "x"],
                                  ["--workers", "2", "--scheduler", "tcp://h:1"]])
@pytest.mark.parametrize("suite", ["agv", "reactive"])
def test_bench_bad_worker_options_exit_2(suite, argv, capsys):
    assert main(["bench", suite, "--n", "2", *argv, "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_bench_agv_on_two_workers_prints_where_and_matches_here(tmp_path, capsys):
    here, there = tmp_path / "here.json", tmp_path / "there.json"
    import json

    for out, workers in ((here, "0"), (there, "2")):
        main(["bench", "agv", "--n", "4", "--seed", "2", "--workers", workers,
              "--json", str(out), "--no-progress"])
    text = capsys.readouterr().out
    assert "on this process" in text and "on 2 local workers" in text
    a, b = json.loads(here.read_text()), json.loads(there.read_text())
    a.pop("seconds"), b.pop("seconds")
    assert a == b
