"""Real cells: scene files v2 (meshes, a tool), their refusals, and detoured tours checked
by coal directly (not through the checker or the planner)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.cell.meshes import box_triangles, write_stl
from subtask_opt.cell.scene import Scene

HOME = np.radians([0.0, -100.0, 100.0, -90.0, -90.0, 0.0])
TCP = 0.15
STANDOFF = 0.05
PILLAR = (0.5, 0.0, 0.55)  # x, y, height (m)
TABLE = {"name": "table", "center": [0.3, 0.0, -0.03], "half_extents": [0.7, 0.7, 0.02]}
DRILL = {"name": "drill", "center": [0, 0, 0.065], "half_extents": [0.02, 0.02, 0.065]}


def _sheet(x0=0.5, z0=0.05, lx=0.3, ly=0.7, curv=0.6, nx=8, ny=16, t=0.004):
    """A curved sheet z = z0 + curv (x - x0)^2, closed (top, bottom), as vertices/triangles."""
    xs, ys = np.linspace(-lx / 2, lx / 2, nx), np.linspace(-ly / 2, ly / 2, ny)
    x, y = np.meshgrid(xs, ys, indexing="ij")
    top = np.stack([x + x0, y, z0 + curv * x ** 2], -1).reshape(-1, 3)
    vertices = np.vstack([top, top - [0, 0, t]])
    n = len(top)
    tris = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            a, b, c, d = i * ny + j, (i + 1) * ny + j, (i + 1) * ny + j + 1, i * ny + j + 1
            tris += [(a, b, c), (a, c, d), (n + a, n + c, n + b), (n + a, n + d, n + c)]
    return vertices, np.array(tris)


def _holes(ys=(-0.3, -0.22, 0.22, 0.3), xs=(0.45, 0.55)) -> str:
    rows = ["x,y,z,dx,dy,dz"]
    for y in ys:
        for x in xs:
            normal = np.array([-1.2 * (x - 0.5), 0.0, 1.0])
            d = -normal / np.linalg.norm(normal)  # drilled into the sheet
            rows.append(f"{x},{y},{0.05 + 0.6 * (x - 0.5) ** 2},{d[0]},{d[1]},{d[2]}")
    return "\n".join(rows) + "\n"


def _cell(folder: Path) -> Path:
    write_stl(folder / "part.stl", *_sheet())
    write_stl(folder / "pillar.stl", *box_triangles([0.04, 0.04, PILLAR[2] / 2]))
    doc = {"note": "two groups of holes with a pillar between",
           "boxes": [TABLE],
           "meshes": [{"name": "part", "file": "part.stl"},
                      {"name": "pillar", "file": "pillar.stl",
                       "position": [PILLAR[0], PILLAR[1], PILLAR[2] / 2]}],
           "tool": {"frame": "tool0", "tcp": {"xyz": [0, 0, TCP]}, "boxes": [DRILL]}}
    (folder / "cell.json").write_text(json.dumps(doc))
    (folder / "holes.csv").write_text(_holes())
    return folder / "cell.json"


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    return _cell(tmp_path_factory.mktemp("cell"))


@pytest.fixture(scope="module")
def solved(cell):
    import subtask_opt as so
    from subtask_opt.arm.problem import ArmProblem, load_robot, load_targets
    from subtask_opt.cell.detour import DetourParams

    robot = load_robot("ur5")
    # the acceptance cell, solved with and without detours (about 8 s in all: the planner
    # and the mesh sweeps of a few hundred legs)
    targets = load_targets(cell.parent / "holes.csv", standoff=STANDOFF, axis_step=45.0)
    out = {}
    for detours in (True, False):
        problem = ArmProblem(targets, robot, home=HOME, scene=cell, detours=detours,
                             detour=DetourParams(max_plans=20, attempts=2) if detours else None)
        out[detours] = (problem, so.solve(problem, seed=3))
    return out


# ------------------------------------------------------------------ scene files, v2

def test_scene_v2_loads_meshes_and_the_tool(cell) -> None:
    scene = Scene.load(cell)
    assert [m.name for m in scene.meshes] == ["part", "pillar"]
    pillar = scene.meshes[1]
    corners = pillar.placed_vertices()
    np.testing.assert_allclose(corners.min(axis=0), [0.46, -0.04, 0.0], atol=1e-6)
    np.testing.assert_allclose(corners.max(axis=0), [0.54, 0.04, PILLAR[2]], atol=1e-6)
    assert scene.tool is not None and scene.tool.frame == "tool0"
    np.testing.assert_allclose(scene.tool.tcp[:3, 3], [0, 0, TCP])


def test_bare_mesh_is_a_scene_of_one_mesh_at_the_origin(cell) -> None:
    scene = Scene.load(cell.parent / "pillar.stl")
    assert scene.boxes == () and scene.tool is None and len(scene.meshes) == 1
    np.testing.assert_allclose(scene.meshes[0].placed_vertices().max(axis=0),
                               [0.04, 0.04, PILLAR[2] / 2], atol=1e-6)


def test_mesh_scale_and_rotation_place_the_vertices(cell, tmp_path) -> None:
    c, s = math.cos(0.4), math.sin(0.4)
    rot = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    write_stl(tmp_path / "p.stl", *box_triangles([0.04, 0.04, 0.275]))
    doc = {"meshes": [{"file": "p.stl", "scale": [2, 1, 0.5], "position": [1, 2, 3],
                       "rotation": rot}]}
    (tmp_path / "s.json").write_text(json.dumps(doc))
    mesh = Scene.load(tmp_path / "s.json").meshes[0]
    local = np.array([[x, y, z] for x in (-0.08, 0.08) for y in (-0.04, 0.04)
                      for z in (-0.1375, 0.1375)])
    expect = local @ np.array(rot).T + [1, 2, 3]
    got = mesh.placed_vertices()
    assert max(np.linalg.norm(got - e, axis=1).min() for e in expect) < 1e-6


def _bad_cases(folder: Path) -> list[tuple[dict, str]]:
    write_stl(folder / "ok.stl", *box_triangles([0.1, 0.1, 0.1]))
    line = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float)
    write_stl(folder / "flat.stl", line, [[0, 1, 2]])
    (folder / "junk.stl").write_bytes(b"not a mesh")
    (folder / "sub").mkdir(exist_ok=True)
    ok = {"file": "ok.stl"}
    flip = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]
    return [
        ({"boxes": [], "colour": "red"}, r"unknown field\(s\) \['colour'\]"),
        ({"note": 3, "boxes": []}, "'note' must be a string"),
        ({"meshes": [{"file": "ok.stl", "color": 1}]}, r"meshes\[0\] has unknown field"),
        ({"meshes": [{"name": "m"}]}, r"meshes\[0\] lacks the field 'file'"),
        ({"meshes": [{"file": "missing.stl"}]}, "mesh file not found"),
        ({"meshes": [{"file": "../ok.stl"}]}, "leaves the scene file's folder"),
        ({"meshes": [{"file": str(folder / "ok.stl")}]}, "relative to the scene file"),
        ({"meshes": [{"file": "file:///etc/passwd"}]}, "relative to the scene file"),
        ({"meshes": [{**ok, "rotation": flip}]}, r"meshes\[0\]\.rotation must be a rotation"),
        ({"meshes": [{**ok, "rotation": [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]}]},
         "must be a rotation"),
        ({"meshes": [{**ok, "scale": 0}]}, r"scale must be a number > 0"),
        ({"meshes": [{**ok, "scale": [1, 1]}]}, r"scale must be a number > 0"),
        ({"meshes": [{**ok, "scale": 1000}]}, r"outside \[0.0001, 100\] m"),
        ({"meshes": [{**ok, "scale": 1e-5}]}, r"outside \[0.0001, 100\] m"),
        ({"meshes": [{"file": "flat.stl"}]}, "degenerate"),
        ({"meshes": [{"file": "junk.stl"}]}, "cannot read mesh file"),
        ({"meshes": [{"file": "sub"}]}, "is a folder"),
        ({"meshes": [{**ok, "name": "a"}, {**ok, "name": "a"}]}, "unique"),
        ({"tool": {"frame": "tool0", "weight": 2}}, r"tool has unknown field\(s\) \['weight'\]"),
        ({"tool": {"tcp": {"xyz": [0, 0, 1]}}}, r"tool\.frame must name a robot frame"),
        ({"tool": {"frame": "tool0", "tcp": {"xyz": [0, 0]}}}, r"tool\.tcp\.xyz must be 3"),
        ({"tool": {"frame": "tool0", "tcp": {"xyz": [0, 0, 0], "quat": [1, 0, 0, 0]}}},
         r"tool\.tcp has unknown field"),
        ({"tool": {"frame": "tool0", "boxes": [{"center": [0, 0, 0]}]}},
         r"tool\.boxes\[0\] lacks the field 'half_extents'"),
        ({"tool": {"frame": "tool0", "meshes": [{"file": "missing.stl"}]}},
         "mesh file not found"),
        ({}, "'boxes', 'meshes' and/or 'tool'"),
    ]


def test_every_bad_scene_is_refused_naming_the_key_or_file(tmp_path) -> None:
    for k, (doc, match) in enumerate(_bad_cases(tmp_path)):
        path = tmp_path / f"bad{k}.json"
        path.write_text(json.dumps(doc))
        with pytest.raises(InputDataError, match=match):
            Scene.load(path)


def test_bad_scenes_exit_2_with_one_line_in_the_cli(tmp_path, capsys) -> None:
    from subtask_opt.cli import main

    (tmp_path / "holes.csv").write_text(_holes())
    cases = _bad_cases(tmp_path)
    for k in (0, 4, 5, 8, 12, 14, 15, 18):
        doc, match = cases[k]
        path = tmp_path / f"bad{k}.json"
        path.write_text(json.dumps(doc))
        code = main(["solve", "--robot", "ur5", "--case", str(tmp_path / "holes.csv"),
                     "--scene", str(path), "--home", "0,-100,100,-90,-90,0", "--seed", "0",
                     "--no-progress"])
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2, (k, err)
        assert len(err) == 1 and pytest.importorskip("re").search(match, err[0]), (k, err)


def test_a_scene_tool_refuses_a_tool_frame_and_an_unknown_frame(cell, tmp_path) -> None:
    from subtask_opt.arm.problem import ArmProblem, load_robot, load_targets

    targets = load_targets(cell.parent / "holes.csv", standoff=STANDOFF, axis_step=90.0)
    with pytest.raises(ParameterError, match="the scene's tool defines the TCP"):
        ArmProblem(targets, load_robot("ur5", tool_frame="tool0"), home=HOME, scene=cell)
    doc = json.loads(cell.read_text())
    doc["tool"]["frame"] = "no_such_frame"
    bad = cell.parent / "bad_frame.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(InputDataError, match="'no_such_frame' is not a frame of ur5"):
        ArmProblem(targets, load_robot("ur5"), home=HOME, scene=bad)


# ------------------------------------------------------------------ the cell, solved

def _tool0(q: np.ndarray) -> np.ndarray:
    from subtask_opt.kinematics.serial import load_serial_arm

    return load_serial_arm("ur5", tool_frame="tool0").fk(q)


def test_every_tcp_reaches_its_hole(solved) -> None:
    # oracle: FK of the bare UR5's tool0, then the TCP offset by hand
    problem, result = solved[True]
    targets = problem.compiled.targets
    for i, q in enumerate(result.configurations):
        tcp = _tool0(q) @ np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, TCP], [0, 0, 0, 1.0]])
        axis = targets.axes[i] / np.linalg.norm(targets.axes[i])
        goal = targets.points[i] - STANDOFF * axis
        assert np.linalg.norm(tcp[:3, 3] - goal) < 1e-5
        assert math.acos(min(1.0, float(tcp[:3, 2] @ axis))) < 1e-4


def _coal_obstacles(cell: Path) -> list[tuple[object, object]]:
    import coal

    table = coal.Box(*(2 * np.array(TABLE["half_extents"])))
    out = [(table, coal.Transform3s(np.eye(3), np.array(TABLE["center"], float)))]
    loader = coal.MeshLoader()
    out.append((loader.load(str(cell.parent / "part.stl"), np.ones(3)), coal.Transform3s()))
    out.append((loader.load(str(cell.parent / "pillar.stl"), np.ones(3)),
                coal.Transform3s(np.eye(3), np.array([PILLAR[0], PILLAR[1], PILLAR[2] / 2]))))
    return out


def test_the_written_trajectory_stays_clear_by_coal_directly(solved, cell) -> None:
    import coal
    import pinocchio as pin

    import subtask_opt as so
    from subtask_opt.kinematics.serial import load_serial_arm

    problem, result = solved[True]
    trajectory = so.trajectory(result)
    assert abs(trajectory.duration - result.total_time) <= 0.005 * result.total_time
    arm = load_serial_arm("ur5")
    model = pin.buildModelFromUrdf(str(arm.urdf_path))
    geom = pin.buildGeomFromUrdf(model, str(arm.urdf_path), pin.GeometryType.COLLISION,
                                 package_dirs=arm.package_dirs)
    data, gdata = model.createData(), geom.createData()
    tool0 = model.getFrameId("tool0")
    drill = coal.Box(*(2 * np.array(DRILL["half_extents"])))
    obstacles = _coal_obstacles(cell)
    moving = [k for k, g in enumerate(geom.geometryObjects) if g.parentJoint > 0]
    q = trajectory.states(trajectory.sample_times(0.004))[0]
    for row in q:
        pin.framesForwardKinematics(model, data, row)
        pin.updateGeometryPlacements(model, data, geom, gdata)
        shapes = [(geom.geometryObjects[k].geometry, gdata.oMg[k]) for k in moving]
        shapes.append((drill, data.oMf[tool0] * pin.SE3(np.eye(3), np.array(DRILL["center"]))))
        for shape, place in shapes:
            tf = coal.Transform3s(np.array(place.rotation), np.array(place.translation))
            for obstacle, where in obstacles:
                res = coal.CollisionResult()
                assert coal.collide(shape, tf, obstacle, where, coal.CollisionRequest(),
                                    res) == 0
    assert so.validate(trajectory).ok


def test_detours_are_taken_and_never_lengthen_the_tour(solved) -> None:
    _, with_detours = solved[True]
    _, without = solved[False]
    counts = with_detours.report.counts
    assert counts["legs_detoured"] >= 1 and counts["legs_planned"] <= 20
    assert without.report.counts["legs_detoured"] == 0
    assert without.report.counts["legs_planned"] == 0
    # the straight legs between the two groups hit the pillar: a detour is shorter
    assert with_detours.total_time < without.total_time
    legs = [leg for leg in __import__("subtask_opt").trajectory(with_detours).legs
            if leg.kind == "detour"]
    assert len(legs) == counts["legs_detoured"]


def test_candidate_legs_plan_detours_too(cell) -> None:
    """The same cell on candidate legs (legs_mode "sparse"): the legs in collision the
    search meets are planned around the pillar as on the dense matrix, the tour is
    shorter than with them forbidden, and its trajectory validates (collisions included)."""
    import subtask_opt as so
    from subtask_opt.arm.problem import load_robot, load_targets
    from subtask_opt.arm.serial_problem import SerialProblem, solve_serial_problem
    from subtask_opt.cell.detour import DetourParams

    robot = load_robot("ur5")
    targets = load_targets(cell.parent / "holes.csv", standoff=STANDOFF, axis_step=45.0)
    out = {}
    for detours in (True, False):
        problem = SerialProblem(targets, robot.model, HOME, scene=Scene.load(cell),
                                detours=detours, legs_mode="sparse",
                                detour=DetourParams(max_plans=20, attempts=2) if detours
                                else None)
        out[detours] = solve_serial_problem(problem, seed=3)
    counts = out[True].report.counts
    assert counts["detours"] and counts["legs_detoured"] >= 1 and counts["legs_planned"] <= 20
    assert out[False].report.counts["legs_detoured"] == 0
    assert out[True].total_time < out[False].total_time
    trajectory = so.trajectory(out[True])
    assert len([leg for leg in trajectory.legs if leg.kind == "detour"]) == counts[
        "legs_detoured"]
    assert so.validate(trajectory).ok
    assert "detoured" in out[True].summary() and "detours off" in out[False].summary()


def test_same_seed_same_detoured_tour(solved) -> None:
    import subtask_opt as so

    problem, first = solved[True]
    again = so.solve(problem, seed=3)
    np.testing.assert_array_equal(again.order, first.order)
    assert again.total_time == first.total_time
    for k, waypoints in first.report.detours.items():
        np.testing.assert_array_equal(again.report.detours[k], waypoints)


def test_cli_takes_a_bare_mesh_as_the_scene(cell, capsys) -> None:
    from subtask_opt.cli import main

    code = main(["solve", "--robot", "ur5", "--case", str(cell.parent / "holes.csv"),
                 "--scene", str(cell.parent / "part.stl"), "--home", "0,-100,100,-90,-90,0",
                 "--standoff", "0.2", "--axis-step", "90", "--seed", "0", "--no-detours",
                 "--no-progress"])
    out = capsys.readouterr()
    assert code == 0, out.err
    assert "detours off" in out.out


def test_plan_after_sequencing_plans_exactly_the_colliding_straight_legs(solved, cell) -> None:
    """RoboTSP's pipeline step (benchmarks/robotsp.py): the detoured tour driven straight
    collides on its detoured legs; planning them after sequencing clears it."""
    import subtask_opt as so
    from subtask_opt.arm.serial_problem import evaluate_tour
    from subtask_opt.papers.robotsp import plan_after

    problem, result = solved[True]
    serial = problem.compiled
    straight = evaluate_tour(serial, result.order, result.report.configuration_index)
    path = [straight.home, *straight.configurations[straight.order], straight.home]
    hits = [k for k in range(len(path) - 1)
            if serial.checker.leg_in_collision(path[k], path[k + 1], serial.clearance)]
    assert hits and set(hits) == set(result.report.detours)
    after = plan_after(serial, straight, seed=1, params=serial.detour)
    assert sorted(after.detours) == hits and after.counts["legs_unplanned"] == 0
    assert after.total_time == pytest.approx(float(after.leg_times.sum()))
    for k, w in after.detours.items():  # each detour joins its leg's two ends
        np.testing.assert_array_equal(w[0], path[k])
        np.testing.assert_array_equal(w[-1], path[k + 1])
    from subtask_opt.arm.trajectory import from_serial_report

    trajectory = from_serial_report(after)
    check = so.validate(trajectory)
    assert check.ok and check.legs_in_collision == 0, check.violations
    assert abs(trajectory.duration - after.total_time) <= 0.005 * after.total_time


def test_curved_sheet_is_closed_and_on_its_parabola(tmp_path) -> None:
    from subtask_opt.cell.meshes import Mesh, curved_sheet

    v, t = curved_sheet((0.5, 0.1, 0.05), (0.3, 0.6), 0.6, thickness=0.004, divisions=(5, 7))
    edges: dict[tuple[int, int], int] = {}
    for tri in t:
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            edges[(min(a, b), max(a, b))] = edges.get((min(a, b), max(a, b)), 0) + 1
    assert set(edges.values()) == {2}  # closed: every edge shared by two triangles
    top = v[: len(v) // 2]
    np.testing.assert_allclose(top[:, 2], 0.05 + 0.6 * (top[:, 0] - 0.5) ** 2)
    np.testing.assert_allclose(v[len(v) // 2:, 2], top[:, 2] - 0.004)
    assert np.ptp(top[:, 1]) == pytest.approx(0.6)
    write_stl(tmp_path / "s.stl", v, t)
    assert Mesh(name="s", file=tmp_path / "s.stl").geometry.num_tris == len(t)
    with pytest.raises(ParameterError, match="divisions must be two ints"):
        curved_sheet(divisions=(1, 5))


_SUBPROCESS_SOLVE = """
import json, sys
import numpy as np
import subtask_opt as so
from subtask_opt.cell.detour import DetourParams
from subtask_opt.arm.problem import ArmProblem, load_robot, load_targets
cell, holes = sys.argv[1], sys.argv[2]
targets = load_targets(holes, standoff=0.05, axis_step=45.0)
problem = ArmProblem(targets, load_robot("ur5"), home=np.radians([0, -100, 100, -90, -90, 0]),
                     scene=cell, detour=DetourParams(max_plans=20, attempts=1))
result = so.solve(problem, seed=3)
print(json.dumps({"order": [int(i) for i in result.order], "total": result.total_time,
                  "detours": {str(k): w.tolist() for k, w in result.report.detours.items()}}))
"""


def test_same_seed_same_detoured_tour_across_processes(cell) -> None:
    """Two fresh interpreters (different hash seeds) plan the same detours bit for bit.
    (About 10 s: two processes, each its own IK, sweeps and plans.)"""
    import os
    import subprocess
    import sys

    answers = []
    for hash_seed in ("1", "2"):
        env = {**os.environ, "PYTHONHASHSEED": hash_seed,
               "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
        run = subprocess.run([sys.executable, "-c", _SUBPROCESS_SOLVE, str(cell),
                              str(cell.parent / "holes.csv")], capture_output=True, text=True,
                             env=env, timeout=300, check=False)
        assert run.returncode == 0, run.stderr[-2000:]
        answers.append(json.loads(run.stdout.strip().splitlines()[-1]))
    assert answers[0]["detours"], "the cell must need a detour for this test to mean anything"
    assert answers[0] == answers[1]


def test_batch_takes_detours_like_the_cli(cell, tmp_path, capsys) -> None:
    import subtask_opt as so
    from subtask_opt.arm.problem import ArmProblem, load_robot, load_targets
    from subtask_opt.cli import main

    holes = cell.parent / "holes.csv"
    solo = so.solve(ArmProblem(load_targets(holes, standoff=STANDOFF), load_robot("ur5"),
                               home=HOME, scene=cell, detours=False), seed=2)
    home = "0,-100,100,-90,-90,0"
    out = tmp_path / "b.json"
    code = main(["batch", str(holes), "--robot", "ur5", "--home", home, "--scene", str(cell),
                 "--standoff", str(STANDOFF), "--no-detours", "--workers", "0", "--seed", "2",
                 "--json", str(out), "--no-progress"])
    assert code == 0, capsys.readouterr().err
    job = json.loads(out.read_text())["jobs"][0]
    assert job["order"] == [int(i) for i in solo.order] and job["total_time"] == solo.total_time
    # a manifest's job says it with "detours": false
    manifest = tmp_path / "jobs.json"
    entry = {"id": "a", "case": str(holes), "robot": "ur5", "home": [0, -100, 100, -90, -90, 0],
             "scene": str(cell), "standoff": STANDOFF, "detours": False, "seed": 2}
    manifest.write_text(json.dumps([entry]))
    assert main(["batch", str(manifest), "--workers", "0", "--json", str(out),
                 "--no-progress"]) == 0
    assert json.loads(out.read_text())["jobs"][0]["total_time"] == solo.total_time
    capsys.readouterr()
    # refusals: one line, exit 2
    planar = tmp_path / "planar.json"
    planar.write_text(json.dumps([{"id": "p", "case": "square20", "detours": False}]))
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps([{**entry, "detours": "no"}]))
    for argv, word in ((["batch", str(planar)], "Job.detours applies to serial arms only"),
                       (["batch", str(bad)], "Job.detours must be true or false"),
                       (["batch", str(manifest), "--no-detours"], "--no-detours applies to")):
        assert main([*argv, "--json", str(tmp_path / "x.json"), "--workers", "0"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and word in err[0], err
