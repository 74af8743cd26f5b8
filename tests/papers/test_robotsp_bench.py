"""RoboTSP's benchmark end to end on its smallest subset (benchmark-sized: ``-m bench``)."""

from __future__ import annotations

import pytest

from tests.conftest import SHARED_DATA

DATA = SHARED_DATA / "robotsp"


@pytest.mark.bench
@pytest.mark.skipif(not (DATA / "targets.csv").is_file(), reason="RoboTSP data missing")
def test_robotsp_25_holes_valid_and_beats_the_stand_in() -> None:
    import importlib.util
    import sys
    from pathlib import Path

    from subtask_opt.papers.robotsp import run

    spec = importlib.util.spec_from_file_location(
        "robotsp_script", Path(__file__).resolve().parents[2] / "benchmarks" / "robotsp.py")
    assert spec is not None and spec.loader is not None
    script = importlib.util.module_from_spec(spec)
    sys.modules["robotsp_script"] = script
    spec.loader.exec_module(script)
    report = run(DATA, sizes=[25], peers=("robotsp",),
                 peer_functions={"robotsp": script.robotsp_stand_in})
    methods = report["subsets"]["25"]["methods"]
    assert methods["ours"]["valid"], methods["ours"]["violations"]
    assert methods["ours"]["legs_in_collision"] == 0
    assert methods["ours"]["executed_time_s"] < methods["robotsp"]["executed_time_s"]
    # RoboTSP's plan-after pipeline: its colliding legs planned, the trajectory clear
    planned = methods["robotsp_planned"]
    assert planned["valid"], planned["violations"]
    assert planned["trajectory_legs_in_collision"] == 0
    assert planned["legs_detoured"] == methods["robotsp"]["legs_in_collision"]
    assert methods["ours"]["trajectory_legs_in_collision"] == 0
    assert methods["ours"]["executed_time_s"] < planned["executed_time_s"]


@pytest.mark.parametrize(("option", "value"), [("runs", 0), ("runs", 1001), ("kicks", -1)])
def test_bad_search_settings_are_refused_before_any_work(tmp_path, option, value) -> None:
    import numpy as np

    from subtask_opt.base.errors import ParameterError
    from subtask_opt.papers.robotsp import run_subset

    with pytest.raises(ParameterError, match=rf"{option} must be an integer in .*got {value}"):
        run_subset(np.zeros((0, 6)), [], data_dir=tmp_path, **{option: value})
