"""VFF and VFH local planners: reach the goal where they can, stall in a trap,
never touch a blocked cell or squeeze through a corner gap, always terminate."""

from __future__ import annotations

import math

import numpy as np
import pytest

from subtask_opt.base.errors import ParameterError, UnreachableError
from subtask_opt.base.geometry import simplify, wrap_angle
from subtask_opt.base.results import PlanResult
from subtask_opt.base.stop import MaxGenerations
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid import vff, vfh
from subtask_opt.planners.grid._local import GridRobotParams, clear_simplify
from subtask_opt.planners.grid.maps import thesis_case
from subtask_opt.planners.grid.world import GridWorld
from tests.planners.grid.test_grid_oracles import path_free, path_violations

MODULES = {"vff": (vff, vff.GridVFFParams), "vfh": (vfh, vfh.GridVFHParams)}


@pytest.mark.parametrize("name", MODULES)
def test_reaches_goal_on_open_map(name):
    module, _ = MODULES[name]
    case = thesis_case("open")
    res = module.plan(case.world, case.start, case.goal)
    assert res.success and res.outcome == "success", res.message
    assert np.allclose(res.path[-1], case.goal) and np.allclose(res.path[0], case.start)
    traj = np.asarray(res.info["trajectory"])
    assert path_violations(case.world.occupancy, traj) == []
    assert path_violations(case.world.occupancy, res.path) == []
    assert res.info["driven_length"] >= math.dist(case.goal, case.start)
    assert res.info["driven_length"] >= res.length - 1e-9  # simplifying never lengthens


@pytest.mark.parametrize("name", MODULES)
def test_trap_reports_a_stall(name):
    module, _ = MODULES[name]
    case = thesis_case("trap")
    res = module.plan(case.world, case.start, case.goal)
    assert not res.success and res.outcome == "stall"
    assert res.message.startswith("stall"), res.message
    assert res.path.shape == (0, 2)
    traj = np.asarray(res.info["trajectory"])
    assert len(traj) == res.info["steps"] + 1
    assert path_violations(case.world.occupancy, traj) == []


@pytest.mark.parametrize("name", MODULES)
def test_step_limit_is_a_timeout(name):
    module, params_cls = MODULES[name]
    case = thesis_case("open")
    robot = GridRobotParams(max_steps=5, stall_steps=50)
    res = module.plan(case.world, case.start, case.goal, params=params_cls(robot=robot))
    assert not res.success and res.outcome == "timeout" and res.info["steps"] == 5


@pytest.mark.parametrize("name", MODULES)
@pytest.mark.parametrize("rows, start, goal", [
    ("@.\n.@", (0, 1), (1, 0)),  # free cells bottom-left and top-right, gap between
    (".@\n@.", (0, 0), (1, 1)),
])
def test_corner_gap_is_a_collision(name, rows, start, goal):
    module, _ = MODULES[name]
    res = module.plan(GridWorld.from_ascii(rows), start, goal)
    assert not res.success and res.outcome == "collision", res.message


@pytest.mark.parametrize("name", MODULES)
def test_start_is_goal(name):
    module, _ = MODULES[name]
    world = GridWorld.from_ascii("...")
    res = module.plan(world, (1, 0), (1, 0))
    assert res.success and res.length == 0.0 and res.info["steps"] == 0


def test_collision_is_reported_where_it_happens():
    # a wall right in front and no repulsion to speak of: the robot drives into it
    world = GridWorld.from_ascii("....\n..@.\n....")
    params = vff.GridVFFParams(f_cr=1e-9, robot=GridRobotParams(window=0.5))
    res = vff.plan(world, (0, 1), (3, 1), params=params)
    assert res.outcome == "collision"
    traj = np.asarray(res.info["trajectory"])
    assert path_violations(world.occupancy, traj[:-1]) == []  # clean until the last step
    assert not path_free(world.occupancy, traj[-2:])  # the last step touches the wall


@pytest.mark.parametrize("name", MODULES)
def test_deterministic_and_json_safe(name):
    module, _ = MODULES[name]
    case = thesis_case("walls")
    a = module.plan(case.world, case.start, case.goal)
    b = module.plan(case.world, case.start, case.goal)
    assert a.info["trajectory"] == b.info["trajectory"]
    assert all(isinstance(p, list) for p in a.info["trajectory"])
    PlanResult(a.path, a.success, a.message, a.planner, info=a.info, outcome=a.outcome)


@pytest.mark.parametrize("name", MODULES)
def test_deterministic_planners_refuse_seed_and_stop(name):
    module, _ = MODULES[name]
    case = thesis_case("open")
    with pytest.raises(ParameterError, match="seed"):
        module.plan(case.world, case.start, case.goal, seed=0)
    with pytest.raises(ParameterError, match="stop"):
        module.plan(case.world, case.start, case.goal, stop=MaxGenerations(3))


def test_move_clear_is_the_segment_hits_rule():
    rng = np.random.default_rng(5)
    occ = rng.random((6, 7)) < 0.3
    blocked = occ.view(np.uint8)
    for _ in range(300):
        x0, x1 = rng.integers(0, 7, 2)
        y0, y1 = rng.integers(0, 6, 2)
        exact = K.segment_hits(blocked, x0, y0, x1, y1, True) == 0
        assert K.move_clear(blocked, float(x0), float(y0), float(x1), float(y1)) == exact


def test_wrap_matches_base_geometry():
    for a in np.linspace(-20, 20, 401):
        assert K.wrap(a) == pytest.approx(wrap_angle(float(a)), abs=1e-12)


def test_polar_histogram_eq_2_7_to_2_10():
    cert = np.zeros((7, 7))
    cert[3, 5] = 2.0  # two cells east of the robot at (3, 3)
    m = 2.0**2 * (1.0 - 0.1 * 2.0)  # eq. 2.8
    raw = K.polar_histogram(cert, 3.0, 3.0, 3.0, 36, 1.0, 0.1, 0, 1.0)
    assert raw[0] == pytest.approx(m) and raw[1:].sum() == 0


@pytest.mark.parametrize("centre, weight", [("printed", 2.0), ("sequence", 3.0)])
def test_polar_histogram_smoothing_eq_2_11(centre, weight):
    cert = np.zeros((7, 7))
    cert[3, 5] = 2.0
    m = 2.0**2 * (1.0 - 0.1 * 2.0)
    params = vfh.GridVFHParams(smoothing=2, centre_weight=centre)
    assert params.centre == weight
    h = K.polar_histogram(cert, 3.0, 3.0, 3.0, 36, 1.0, 0.1, 2, params.centre)
    # l = 2: sector 0 gets the centre weight, its neighbours 2 and 1, over 2l + 1 = 5
    assert h[0] == pytest.approx(weight * m / 5)
    assert h[1] == pytest.approx(2 * m / 5) and h[35] == pytest.approx(2 * m / 5)
    assert h[2] == pytest.approx(m / 5) and h[34] == pytest.approx(m / 5)
    assert h[3:34].sum() == 0


def test_vfh_steer_valleys():
    smooth = np.zeros(36)
    assert K.vfh_steer(smooth, 5, 1.0, 6) == 5.0  # free target in a wide valley
    smooth[2:8] = 10.0  # target blocked; nearest free sector 8 (3 away; 1 is 4 away)
    assert K.vfh_steer(smooth, 5, 1.0, 4) == pytest.approx((8 + 11) / 2)  # valley 8..11
    smooth[:] = 0.0
    smooth[3:9] = 10.0  # nearest free sector 2 (3 away): the valley runs 2, 1, 0, 35
    assert K.vfh_steer(smooth, 5, 1.0, 4) == pytest.approx((2 + -1) / 2)
    assert K.vfh_steer(np.full(36, 10.0), 5, 1.0, 4) == -1.0


def test_clear_simplify_keeps_corners_and_clear_chords():
    world = GridWorld.from_ascii("...\n.@.\n...")
    # round the corner (1.5, 0.5) of the blocked centre; the plain simplified
    # chord (1.48, 0.45) -> (1.55, 2) would clip that corner
    path = np.array([[0, 0.45], [1.48, 0.45], [1.55, 0.52], [1.55, 2]], dtype=float)
    assert path_free(world.occupancy, path)
    assert not path_free(world.occupancy, simplify(path, 0.1))
    out = clear_simplify(world, path, tol=0.1)
    assert path_free(world.occupancy, out) and path_violations(world.occupancy, out) == []
    assert out.tolist() == path.tolist()
    straight = np.array([[0, 0], [1, 0.01], [2, 0]], dtype=float)
    assert clear_simplify(world, straight).tolist() == [[0, 0], [2, 0]]


@pytest.mark.parametrize("make, field", [
    (lambda: GridRobotParams(speed=0), "speed"), (lambda: GridRobotParams(speed=0.8), "speed"),
    (lambda: GridRobotParams(max_steps=0), "max_steps"),
    (lambda: GridRobotParams(stall_radius=-1), "stall_radius"),
    (lambda: vff.GridVFFParams(f_cr=-1), "f_cr"), (lambda: vfh.GridVFHParams(alpha_deg=7), "alpha"),
    (lambda: vfh.GridVFHParams(threshold=0), "threshold"),
    (lambda: vfh.GridVFHParams(smoothing=-1), "smoothing"),
    (lambda: vfh.GridVFHParams(centre_weight="l"), "centre_weight"),
])
def test_bad_params(make, field):
    with pytest.raises(ParameterError, match=field):
        make()


def test_bad_cells():
    case = thesis_case("open")
    with pytest.raises(UnreachableError, match="start"):
        vfh.plan(case.world, (0, 0), case.goal)
