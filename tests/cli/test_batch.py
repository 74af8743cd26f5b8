"""`subtask-opt batch`: JSON per job, exit codes 0/1/2, one-line errors."""

from __future__ import annotations

import json

import pytest

from subtask_opt import solve
from subtask_opt.arm.planar_problem import PlanarProblem
from subtask_opt.arm.tasks import builtin_case, random_subtasks, save_subtasks
from subtask_opt.base.stop import MaxGenerations
from subtask_opt.batch.pool import dask_available
from subtask_opt.cli.app import main
from subtask_opt.kinematics.planar import load_planar_arm

GENERATIONS = 30


@pytest.fixture(scope="module")
def arm():
    return load_planar_arm("planar_2r")


@pytest.fixture
def parts(tmp_path, arm):
    """Two subtask files and a manifest of two more jobs (one file, one built-in case)."""
    save_subtasks(random_subtasks(arm, 6, seed=1), tmp_path / "a.csv")
    save_subtasks(random_subtasks(arm, 7, seed=2), tmp_path / "b.json")
    (tmp_path / "jobs.json").write_text(json.dumps({"jobs": [
        {"id": "m-a", "case": "a.csv", "time_model": "trapezoid", "seed": 5},
        {"id": "m-sq", "case": "square20", "time_model": "paper", "seed": 2},
    ]}))
    return tmp_path


def _run(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def _solve(subtasks, arm, time_model, seed):
    problem = PlanarProblem(subtasks, arm, time_model=time_model)
    return solve(problem, seed=seed, stop=MaxGenerations(GENERATIONS))


def test_batch_writes_one_result_per_job_equal_to_solve(parts, arm, capsys):
    out = parts / "out.json"
    argv = ["batch", str(parts / "a.csv"), str(parts / "b.json"), str(parts / "jobs.json"),
            "--workers", "0", "--max-generations", str(GENERATIONS), "--json", str(out),
            "--no-progress"]
    code, printed, err = _run(argv, capsys)
    assert code == 0, err
    assert "4 jobs: 4 solved, 0 failed" in printed
    data = json.loads(out.read_text())
    jobs = {j["id"]: j for j in data["jobs"]}
    assert list(jobs) == [str(parts / "a.csv"), str(parts / "b.json"), "m-a", "m-sq"]
    assert data["summary"]["jobs"] == 4 and data["summary"]["failed"] == 0
    want = {
        str(parts / "a.csv"): _solve(random_subtasks(arm, 6, seed=1), arm, "joint", 0),
        str(parts / "b.json"): _solve(random_subtasks(arm, 7, seed=2), arm, "joint", 0),
        "m-a": _solve(random_subtasks(arm, 6, seed=1), arm, "trapezoid", 5),
        "m-sq": _solve(builtin_case("square20", arm), arm, "paper", 2),
    }
    for ident, result in want.items():
        assert jobs[ident]["success"] and jobs[ident]["error"] is None
        assert jobs[ident]["order"] == [int(i) for i in result.order]
        assert jobs[ident]["total_time"] == result.total_time


def test_seed_option_overrides_every_jobs_seed(parts, capsys):
    out = parts / "out.json"
    code, _, err = _run(["batch", str(parts / "jobs.json"), "--workers", "0", "--seed", "11",
                         "--max-generations", "3", "--json", str(out)], capsys)
    assert code == 0, err
    assert [j["seed"] for j in json.loads(out.read_text())["jobs"]] == [11, 11]


def test_failed_jobs_exit_1_with_their_errors_in_the_json(parts, capsys):
    (parts / "bad.csv").write_text("x,y\n0.3,0.1\n0.3,0.1\n0.25,0.3\n")
    (parts / "more.json").write_text(json.dumps([
        {"id": "gone", "case": "missing.csv"}, {"id": "ok", "case": "a.csv"}]))
    out = parts / "out.json"
    code, printed, _ = _run(["batch", str(parts / "bad.csv"), str(parts / "more.json"),
                             "--workers", "0", "--max-generations", "3", "--json", str(out)],
                            capsys)
    assert code == 1
    jobs = {j["id"]: j for j in json.loads(out.read_text())["jobs"]}
    assert not jobs[str(parts / "bad.csv")]["success"]
    assert "duplicate" in jobs[str(parts / "bad.csv")]["error"]
    assert not jobs["gone"]["success"] and "missing.csv" in jobs["gone"]["error"]
    assert jobs["ok"]["success"] and sorted(jobs["ok"]["order"]) == list(range(6))
    assert "3 jobs: 1 solved, 2 failed" in printed and "failed gone:" in printed


@pytest.mark.skipif(not dask_available(), reason="needs subtask_opt[cluster]")
def test_two_local_workers_give_the_serial_answers(parts, capsys):
    outs = []
    for workers in ("0", "2"):
        out = parts / f"out{workers}.json"
        code, _, err = _run(["batch", str(parts / "jobs.json"), str(parts / "a.csv"),
                             "--workers", workers, "--max-generations", "20",
                             "--json", str(out)], capsys)
        assert code == 0, err
        outs.append([(j["id"], j["order"], j["total_time"])
                     for j in json.loads(out.read_text())["jobs"]])
    assert outs[0] == outs[1]


@pytest.mark.parametrize(("argv", "needle"), [
    (["batch", "nowhere.csv", "--json", "o.json"], "nowhere.csv"),
    (["batch", "{parts}/a.csv", "--workers", "-1", "--json", "o.json"], "-1"),
    (["batch", "{parts}/a.csv", "--seed", "-3", "--json", "o.json"], "-3"),
    (["batch", "{parts}/a.csv", "--workers", "2", "--scheduler", "tcp://h:1",
      "--json", "o.json"], "--scheduler"),
    (["batch", "{parts}/a.csv"], "--json"),
    (["batch", "{parts}/a.csv", "--json", "{parts}/a.csv"], "a.csv"),
    (["batch", "{parts}/a.csv", "--scheduler", "h:8786", "--json", "o.json"], "h:8786"),
    (["batch", "{parts}/bad_manifest.json", "--json", "o.json"], "'speed'"),
])
def test_bad_input_prints_one_line_and_exits_2(parts, argv, needle, capsys, monkeypatch):
    monkeypatch.chdir(parts)
    (parts / "bad_manifest.json").write_text('[{"id": "a", "case": "a.csv", "speed": 2}]')
    argv = [a.replace("{parts}", str(parts)) for a in argv]
    code, _, err = _run(argv, capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1, err
    assert needle in err
    assert not (parts / "o.json").exists()


UR5_ROWS = ("x,y,z,dx,dy,dz\n0.45,-0.15,0.20,1,0,-0.3\n0.45,0.05,0.20,1,0,-0.3\n"
            "0.42,-0.10,0.35,1,0,-0.3\n0.42,0.10,0.35,1,0,-0.3\n")


def test_a_serial_arm_batch_of_target_files_and_its_refusals(tmp_path, capsys):
    import numpy as np

    import subtask_opt as so

    files = []
    for k in range(2):
        path = tmp_path / f"holes{k}.csv"
        lines = UR5_ROWS.splitlines()
        path.write_text("\n".join([lines[0], *lines[1 + k:]]) + "\n")
        files.append(path)
    out = tmp_path / "b.json"
    home = "0,-90,90,-90,-90,0"
    code = main(["batch", *map(str, files), "--robot", "ur5", "--home", home, "--workers",
                 "0", "--seed", "4", "--json", str(out)])
    assert code == 0
    jobs = {j["id"]: j for j in json.loads(out.read_text())["jobs"]}
    for path in files:
        solo = so.solve(so.ArmProblem(so.load_targets(path), so.load_robot("ur5"),
                                      home=np.radians([0, -90, 90, -90, -90, 0])), seed=4)
        assert jobs[str(path)]["order"] == [int(i) for i in solo.order]
        assert jobs[str(path)]["total_time"] == solo.total_time
    capsys.readouterr()
    manifest = tmp_path / "jobs.json"
    manifest.write_text(json.dumps([{"id": "a", "case": "square20"}]))
    for argv, word in ((["batch", str(manifest), "--robot", "ur5"], "--robot"),
                       (["batch", str(files[0]), "--scene", str(manifest)], "scene"),
                       (["batch", str(files[0]), "--robot", "ur5", "--time-model", "line"],
                        "time_model")):
        assert main([*argv, "--json", str(tmp_path / "x.json"), "--workers", "0"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and word in err[0], err
