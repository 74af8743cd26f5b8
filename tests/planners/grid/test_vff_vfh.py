"""VFF and VFH local planners: reach the goal where they can, stall in a trap,
always terminate."""

from __future__ import annotations

import numpy as np
import pytest

from subtask_opt.base.errors import ParameterError, UnreachableError
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid import vff, vfh
from subtask_opt.planners.grid.maps import thesis_case
from tests.planners.grid.test_grid_oracles import path_free

PLANNERS = [vff, vfh]


@pytest.mark.parametrize("module", PLANNERS)
def test_reaches_goal_on_open_map(module):
    case = thesis_case("open")
    res = module.plan(case.world, case.start, case.goal)
    assert res.success, res.message
    assert np.allclose(res.path[-1], case.goal) and np.allclose(res.path[0], case.start)
    traj = res.info["trajectory"]
    cells = np.floor(traj + 0.5).astype(int)
    assert not case.world.occupancy[cells[:, 1], cells[:, 0]].any()
    assert res.info["driven_length"] >= np.hypot(*np.subtract(case.goal, case.start))


@pytest.mark.parametrize("module", PLANNERS)
def test_trap_reports_a_stall(module):
    case = thesis_case("trap")
    res = module.plan(case.world, case.start, case.goal)
    assert not res.success
    assert res.message.startswith("stall"), res.message
    assert res.info["steps"] < res.info["trajectory"].shape[0] + 1


@pytest.mark.parametrize("module", PLANNERS)
def test_step_limit_ends_every_run(module):
    case = thesis_case("cluttered")
    params_cls = module.VFFParams if module is vff else module.VFHParams
    robot = vff.RobotParams(max_steps=5, stall_steps=50)
    res = module.plan(case.world, case.start, case.goal, params=params_cls(robot=robot))
    assert not res.success and res.info["steps"] <= 5


def test_deterministic():
    case = thesis_case("walls")
    a, b = vff.plan(case.world, case.start, case.goal), vff.plan(case.world, case.start, case.goal)
    assert np.array_equal(a.info["trajectory"], b.info["trajectory"])


def test_polar_histogram_eq_2_7_to_2_11():
    cert = np.zeros((7, 7))
    cert[3, 5] = 2.0  # two cells east of the robot at (3, 3)
    h = K.polar_histogram(cert, 3.0, 3.0, 3.0, 36, 1.0, 0.1, 1)
    m = 2.0**2 * (1.0 - 0.1 * 2.0)
    # sector 0 gets weight l+1 = 2, its neighbours 1, divided by 2l+1 = 3
    assert h[0] == pytest.approx(2 * m / 3)
    assert h[1] == pytest.approx(m / 3) and h[35] == pytest.approx(m / 3)
    assert h[2:35].sum() == 0


def test_vfh_steer_valleys():
    smooth = np.zeros(36)
    assert K.vfh_steer(smooth, 5, 1.0, 6) == 5.0  # free target in a wide valley
    smooth[3:9] = 10.0  # target sector blocked
    k = K.vfh_steer(smooth, 5, 1.0, 4)
    assert k == pytest.approx(10.5) or k == pytest.approx(0.5)
    assert K.vfh_steer(np.full(36, 10.0), 5, 1.0, 4) == -1.0


def test_simplify_keeps_corners():
    path = np.array([[0, 0], [1, 0.01], [2, 0], [2, 1], [2, 2]], dtype=float)
    out = vff.simplify(path, tol=0.05)
    assert out.tolist() == [[0, 0], [2, 0], [2, 2]]
    assert path_free(np.zeros((3, 3), bool), out)


@pytest.mark.parametrize("make", [
    lambda: vff.RobotParams(speed=0), lambda: vff.RobotParams(max_steps=0),
    lambda: vff.VFFParams(f_cr=-1), lambda: vfh.VFHParams(alpha_deg=7),
    lambda: vfh.VFHParams(threshold=0), lambda: vfh.VFHParams(smoothing=-1),
])
def test_bad_params(make):
    with pytest.raises(ParameterError):
        make()


def test_bad_cells():
    case = thesis_case("open")
    with pytest.raises(UnreachableError, match="start"):
        vfh.plan(case.world, (0, 0), case.goal)
