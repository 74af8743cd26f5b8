"""The arm side of the candidate legs: the exact dominance rule, the per-target cap,
the closed-form leg bound and a sparse SerialProblem, against brute force and exact
oracles (Held-Karp over every configuration)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from subtask_opt.arm import sparse_legs as sl
from subtask_opt.arm.panel import wing_panel
from subtask_opt.arm.poses import make_targets
from subtask_opt.base.errors import ParameterError
from subtask_opt.kinematics.ik import IKParams, IKSolver
from subtask_opt.kinematics.joint_moves import joint_leg_square, joint_leg_times, joint_limits
from subtask_opt.kinematics.serial import load_serial_arm
from subtask_opt.tour.exact import clustered_held_karp

HOME = np.radians([0.0, -60.0, 90.0, -30.0, 90.0, 0.0])


@pytest.fixture(scope="module")
def ur10():
    return load_serial_arm("ur10")


def _limits(arm):
    return joint_limits(arm.limits.velocity, arm.limits.acceleration)


def _solutions(arm, n, seed, wrap=False, rows=None):
    rows = wing_panel(n, seed=seed) if rows is None else rows
    targets = make_targets(rows, axis_step=90.0, standoff=0.01)
    sol = IKSolver(arm, IKParams(wrap_alternatives=wrap)).solve_targets(targets.poses)
    flat = np.vstack(sol.configurations)
    off = np.concatenate([[0], np.cumsum(sol.counts)]).astype(np.int64)
    points = np.array([p[0, :3, 3] for p in targets.poses])
    return flat, off, points


def test_cartesian_bound_never_exceeds_a_leg(ur10):
    """Brute force: random configuration pairs, the tool points' distance by FK."""
    lim = _limits(ur10)
    levers = sl.reach_levers(ur10)
    rng = np.random.default_rng(0)
    qa = rng.uniform(-math.pi, math.pi, (300, 6))
    qb = qa + rng.normal(0, 0.3, (300, 6)) * rng.uniform(0, 1, (300, 1))
    pairs = list(zip(qa, qb, strict=True))
    d = np.array([np.linalg.norm(ur10.fk(a)[:3, 3] - ur10.fk(b)[:3, 3]) for a, b in pairs])
    t = np.array([joint_leg_times(a, b, lim)[0, 0] for a, b in pairs])
    lb = sl.cartesian_leg_bound(d, levers, lim)
    assert np.all(lb <= t * (1 + 1e-12))
    assert np.median(lb / t) > 0.2  # not a trivial bound


def _optimum(flat, off, lim):
    legs = joint_leg_square(flat, lim)
    home = joint_leg_times(HOME, flat, lim)[0]
    return clustered_held_karp(legs, off, home, home)


def test_dominated_alternatives_keep_the_optimum(ur10):
    """The exact rule, checked: Held-Karp over every configuration equals Held-Karp over
    those not dominated. Target 0 has its +-2 pi alternatives, the others only their
    canonical solutions, so the rule has alternatives to drop."""
    lim = _limits(ur10)
    wrapped, woff, _ = _solutions(ur10, 5, 1, wrap=True)
    plain, poff, _ = _solutions(ur10, 5, 1, wrap=False)
    rows0 = np.arange(woff[0], woff[1])
    rows0 = rows0[np.isin(np.mod(wrapped[rows0] + math.pi, 2 * math.pi).round(6)[:, None],
                          np.mod(plain[:6] + math.pi, 2 * math.pi).round(6)[None]
                          ).all(axis=2).any(axis=1)]  # the alternatives of 6 solutions
    flat = np.vstack([wrapped[rows0], plain[poff[1]:poff[5]]])
    counts = [rows0.size] + [int(poff[t + 1] - poff[t]) for t in range(1, 5)]
    off = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    canon = np.mod(flat + math.pi, 2 * math.pi).round(6)
    _, group = np.unique(canon, axis=0, return_inverse=True)
    drop = sl.dominated(flat, off, group.ravel().astype(np.int64), HOME)
    assert drop.any() and not drop[off[1]:].any()
    kept_off = np.concatenate([[0], np.cumsum(np.add.reduceat((~drop).astype(int),
                                                                off[:-1]))]).astype(np.int64)
    assert _optimum(flat[~drop], kept_off, lim) == pytest.approx(_optimum(flat, off, lim),
                                                                 rel=1e-12)


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_cap_keeps_the_optimum_on_held_out_panels(ur10, seed):
    """The stated criterion of keep_best (not a proof): on held-out 6-hole panel patches
    (seeds never used to tune it), the optimum over the kept configurations equals the
    optimum over all of them (Held-Karp, every configuration)."""
    lim = _limits(ur10)
    rows = wing_panel(400, seed=seed)
    pick = np.argsort(np.linalg.norm(rows[:, :3] - rows[seed % 400, :3], axis=1))[:6]
    flat, off, points = _solutions(ur10, 6, seed, rows=rows[pick])
    home = joint_leg_times(HOME, flat, lim)[0]
    keep = sl.keep_best(flat, off, points, home, lim, 8)
    assert keep.sum() < flat.shape[0]
    kept_off = np.concatenate([[0], np.cumsum(np.add.reduceat(keep.astype(int),
                                                                off[:-1]))]).astype(np.int64)
    assert _optimum(flat[keep], kept_off, lim) == pytest.approx(_optimum(flat, off, lim),
                                                                rel=1e-9)


def test_bound_inputs_with_every_pair_known_bound_no_other_pair(ur10):
    """With k_bound >= N - 1 every pair is an edge with its exact cheapest leg (brute
    force by joint_leg_times), so no other pair needs a bound: rho is +inf (a finite rho
    would only weaken the 1-tree through its star)."""
    flat, off, points = _solutions(ur10, 6, seed=2)
    lim = _limits(ur10)
    home = joint_leg_times(HOME, flat, lim)[0]
    edges, weights, rho, home_min = sl.bound_inputs(flat, off, points, home, lim,
                                                    sl.reach_levers(ur10), k_bound=10)
    assert edges.shape[0] == 15 and np.all(np.isinf(rho))
    for (a, b), w in zip(edges, weights, strict=True):
        block = joint_leg_times(flat[off[a]:off[a + 1]], flat[off[b]:off[b + 1]], lim)
        assert w == pytest.approx(block.min(), rel=1e-12)
    np.testing.assert_allclose(home_min, np.minimum.reduceat(home, off[:-1]))
    *_, rho_few, _ = sl.bound_inputs(flat, off, points, home, lim, sl.reach_levers(ur10),
                                     k_bound=3)
    assert np.all(np.isfinite(rho_few))


@pytest.mark.parametrize("query", [1, 4, 10_000])
def test_far_joint_bound_never_exceeds_a_far_leg(ur10, query):
    """Brute force by joint_leg_times: every leg from a target's configurations to those
    of a target beyond its k nearest is at least the target's far_joint_bound, whether
    the query finds a far configuration (10,000: every one returned), falls back to its
    last distance (1, 4) or not; and with every configuration queried the bound is the
    least such leg's single-joint part, so no weaker than a fifth of the least far leg."""
    flat, off, points = _solutions(ur10, 12, seed=4)
    lim = _limits(ur10)
    near = sl.nearest_targets(points, 3)
    bound = sl.far_joint_bound(flat, off, near, lim, query=query)
    n = off.shape[0] - 1
    for a in range(n):
        far = [b for b in range(n) if b != a and b not in near[a]]
        least = min(joint_leg_times(flat[off[a]:off[a + 1]], flat[off[b]:off[b + 1]],
                                    lim).min() for b in far)
        assert bound[a] <= least * (1 + 1e-12)
        if query >= flat.shape[0]:
            assert bound[a] >= 0.2 * least


def test_bound_inputs_rho_bounds_every_pair_that_is_not_an_edge(ur10):
    """Brute force: with k_bound = 2, every pair of targets that is not an edge costs at
    least (rho_a + rho_b) / 2, and the joint-space part makes rho no smaller than the
    closed-form bound alone (far_query=0)."""
    flat, off, points = _solutions(ur10, 12, seed=6)
    lim = _limits(ur10)
    home = joint_leg_times(HOME, flat, lim)[0]
    levers = sl.reach_levers(ur10)
    edges, _, rho, _ = sl.bound_inputs(flat, off, points, home, lim, levers, k_bound=2)
    *_, rho_cart, _ = sl.bound_inputs(flat, off, points, home, lim, levers, k_bound=2,
                                      far_query=0)
    assert np.all(rho >= rho_cart) and np.any(rho > rho_cart)
    known = {tuple(e) for e in edges.tolist()}
    n = off.shape[0] - 1
    for a in range(n):
        for b in range(a + 1, n):
            if (a, b) not in known:
                block = joint_leg_times(flat[off[a]:off[a + 1]], flat[off[b]:off[b + 1]], lim)
                assert block.min() >= 0.5 * (rho[a] + rho[b]) * (1 - 1e-12)


@pytest.mark.parametrize("seed", [7, 8, 9])
def test_sparse_bound_stays_below_the_exact_optimum(ur10, seed):
    """The 1-tree bound on bound_inputs with few exact pairs (k_bound = 2, so most pairs
    take rho) never exceeds the exact optimum over every configuration (clustered
    Held-Karp), and the joint-space part of rho never lowers it."""
    from subtask_opt.tour.sparse import one_tree_bound

    flat, off, points = _solutions(ur10, 9, seed=seed)
    lim = _limits(ur10)
    home = joint_leg_times(HOME, flat, lim)[0]
    optimum = _optimum(flat, off, lim)
    levers = sl.reach_levers(ur10)
    n = off.shape[0] - 1
    values = []
    for far_query in (0, sl.FAR_QUERY):
        edges, weights, rho, home_min = sl.bound_inputs(flat, off, points, home, lim, levers,
                                                        k_bound=2, far_query=far_query)
        values.append(one_tree_bound(n, edges, weights, rho, home_min, upper=optimum * 1.1))
    assert 0 < values[0] <= values[1] * (1 + 1e-9)
    assert values[1] <= optimum * (1 + 1e-9)


def test_memory_check_refuses_before_work():
    with pytest.raises(ParameterError, match="GiB"):
        sl.check_memory(2**40, limit=2**30)
    sl.check_memory(10, limit=2**30)


def test_among_obstacles_the_cap_keeps_more_configurations_of_fewer_targets():
    assert sl.cap_for(50, False) == sl.DEFAULT_CAP == sl.cap_for(10**6, True)
    assert sl.cap_for(50, True) == sl.CONFIGURATION_BUDGET // 50 > sl.DEFAULT_CAP
    caps = [sl.cap_for(n, True) for n in range(1, 3000, 7)]
    assert caps == sorted(caps, reverse=True) and min(caps) == sl.DEFAULT_CAP
    # the memory check counts the configurations a cap keeps
    assert sl.memory_estimate(10**5, 50, cap=sl.cap_for(50, True)) > sl.memory_estimate(10**5, 50)


def test_sparse_cell_keeps_only_free_configurations_and_counts_the_rest():
    """The UR5 example cell on candidate legs: every kept configuration is collision-free
    by the cell's checker, each target keeps at most cap_for(N) + 1, and the kept,
    collided and capped configurations add up to the non-dominated IK solutions."""
    from pathlib import Path

    from subtask_opt.arm.poses import load_targets
    from subtask_opt.arm.serial_problem import SerialProblem, solve_serial_problem
    from subtask_opt.cell.scene import Scene

    data = Path(__file__).resolve().parents[2] / "examples" / "data"
    targets = load_targets(data / "ur5_panel.csv", standoff=0.01)
    arm = load_serial_arm("ur5")
    home = np.radians([0.0, -90.0, 90.0, -90.0, -90.0, 0.0])
    problem = SerialProblem(targets, arm, home, scene=Scene.load(data / "ur5_panel_scene.json"),
                            legs_mode="sparse")
    assert all(not problem.checker.in_collision(q) for q in problem.flat)
    assert int(problem.counts.max()) <= sl.cap_for(len(targets), True) + 1
    solver = IKSolver(problem.arm, IKParams(wrap_alternatives=False))  # SerialProblem's
    solutions = solver.solve_targets(targets.poses)
    assert (problem.offsets[-1] + problem.dropped_in_collision + problem.dropped_by_cap
            + problem.dropped_dominated) == sum(solutions.counts)
    result = solve_serial_problem(problem, seed=0)
    assert sorted(result.order.tolist()) == list(range(len(targets)))
    assert result.lower_bound <= result.report.planned_time * (1 + 1e-9)


def test_sparse_problem_matches_dense_on_a_small_panel(ur10):
    """The same 30 holes with the dense matrix and the candidate legs, the same seed: the
    sparse answer is no longer than the dense one by more than 0.5%, both above the
    sparse bound, and the sparse leg interface reads the legs joint_leg_times gives."""
    from subtask_opt.arm.serial_problem import SerialProblem, solve_serial_problem

    targets = make_targets(wing_panel(30, seed=4), axis_step=90.0, standoff=0.01)
    dense = SerialProblem(targets, ur10, HOME, legs_mode="dense")
    sparse = SerialProblem(targets, ur10, HOME, legs_mode="sparse")
    rd = solve_serial_problem(dense, seed=0)
    rs = solve_serial_problem(sparse, seed=0)
    assert rs.lower_bound is not None
    assert rs.lower_bound <= rd.report.planned_time * (1 + 1e-9)
    assert rs.lower_bound <= rs.report.planned_time * (1 + 1e-9)
    assert rs.report.planned_time <= rd.report.planned_time * 1.005
    a, b = 0, int(sparse.offsets[1])  # two configurations of neighbouring targets
    nb = int(sparse.sparse.nbr[0, 0])
    b = int(sparse.offsets[nb])
    from subtask_opt.tour.lazy import mark_sparse_leg, sparse_leg_time

    old = sparse_leg_time(sparse.sparse, a, b)
    assert old == pytest.approx(
        joint_leg_times(sparse.flat[a], sparse.flat[b], sparse.limits)[0, 0], rel=1e-12)
    mark_sparse_leg(sparse.sparse, a, b, sparse.penalty)
    assert sparse_leg_time(sparse.sparse, b, a) == sparse.penalty
    mark_sparse_leg(sparse.sparse, a, b, old)
    with pytest.raises(ParameterError, match="legs_mode"):
        SerialProblem(targets, ur10, HOME, legs_mode="matrix")
    from subtask_opt.tour.constraints import TourConstraints

    with pytest.raises(ParameterError, match="closed tours"):
        solve_serial_problem(sparse, seed=0, constraints=TourConstraints(start=1))
