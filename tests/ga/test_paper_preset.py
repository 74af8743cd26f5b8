"""The sequencing paper's micro-GA readings (GAConfig pairing / convergence / crossover
start / distinct mates), the paper preset's loop, and the enumeration of all optima."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from subtask_opt import SolverParams, solve
from subtask_opt.arm.planar_problem import PlanarProblem
from subtask_opt.base.errors import ParameterError, SubtaskOptError
from subtask_opt.base.stop import MaxGenerations
from subtask_opt.chromosomes import use
from subtask_opt.ga.config import CONVERGENCE_TESTS, CROSSOVER_STARTS, PAIRINGS, GAConfig
from subtask_opt.ga.kinds import Kind
from subtask_opt.ga.loop import _draw_mates, _edges_converged, _rotate_to, run_ga
from subtask_opt.tour.exact import held_karp, milp_optimum, optimal_tours, tour_length
from subtask_opt.tour.permutation import make_aux, neighbour_table
from subtask_opt.tour.problem import MatrixProblem
from subtask_opt.tour.solve import PAPER_LOOP

highspy = pytest.importorskip("highspy")


def _euclid(points: np.ndarray) -> np.ndarray:
    return np.hypot(*(points[:, None] - points[None]).transpose(2, 0, 1))


def _lattice(cols: int, rows: int) -> np.ndarray:
    return np.array([(x, y) for y in range(rows) for x in range(cols)], dtype=float)


def _edge_set(order) -> frozenset:
    order = [int(c) for c in order]
    return frozenset(frozenset(e) for e in zip(order, order[1:] + order[:1], strict=True))


def _random_matrix(seed: int, n: int) -> np.ndarray:
    return _euclid(np.random.default_rng(seed).random((n, 2)))


# --- readings: validation and reproducibility ------------------------------------------


@pytest.mark.parametrize(("field", "value"), [("pairing", "ring"), ("convergence", "bits"),
                                              ("crossover_start", 0), ("distinct_mates", 1)])
def test_reading_fields_are_validated(field, value):
    with pytest.raises(ParameterError, match=rf"GAConfig\.{field} .*{value!r}"):
        GAConfig(**{field: value})


READING_GRID = [GAConfig(pairing=p, convergence=c, convergence_tol=0.05)
                for p in PAIRINGS for c in CONVERGENCE_TESTS]
READING_GRID += [GAConfig(crossover_start=s, distinct_mates=True, tournament=2)
                 for s in CROSSOVER_STARTS]


@pytest.mark.parametrize("config", READING_GRID, ids=repr)
def test_every_reading_is_reproducible_and_returns_a_tour(config):
    m = _random_matrix(3, 11)
    aux = make_aux(neighbour_table(m), nearest_fallback=False)

    def run(seed):
        return run_ga(use(Kind.PERMUTATION), config, m, aux, max_genes=11, seed=seed,
                      criteria=[MaxGenerations(200)])

    a, b = run(4), run(4)
    np.testing.assert_array_equal(a.genes, b.genes)
    np.testing.assert_array_equal(a.history.best_cost, b.history.best_cost)
    assert sorted(a.genes.tolist()) == list(range(11))
    assert a.cost == pytest.approx(tour_length(m, a.genes))
    assert np.all(np.diff(a.history.best_cost) <= 0)  # elitism: the best never gets worse


# --- readings: the pieces ------------------------------------------------------------


def _population(rows):
    pop = np.array(rows, dtype=np.int64)
    return pop, np.full(len(rows), pop.shape[1], dtype=np.int64)


def test_rest_pairing_mates_the_four_non_elite_strings_round_a_ring():
    rng = np.random.default_rng(0)
    costs = np.array([3.0, 1.0, 5.0, 2.0, 4.0])
    order = np.array([1, 3, 0, 4, 2])  # elite = string 1
    pop, lengths = _population([[0, 1, 2]] * 5)
    for _ in range(50):
        mates = np.zeros((4, 2), dtype=np.int64)
        _draw_mates(PAIRINGS.index("rest"), costs, order, 1, 4, 0, False, pop, lengths, rng,
                    mates)
        assert 1 not in mates  # the elite only passes on unchanged
        assert np.all(mates[:, 0] != mates[:, 1])
        assert sorted(mates[:, 0].tolist()) == [0, 2, 3, 4]  # each first parent once
        np.testing.assert_array_equal(mates[:, 1], np.roll(mates[:, 0], -1))  # a ring


def test_shuffle_pairing_chains_all_five_strings():
    rng = np.random.default_rng(1)
    costs = np.array([3.0, 1.0, 5.0, 2.0, 4.0])
    order = np.array([1, 3, 0, 4, 2])
    pop, lengths = _population([[0, 1, 2]] * 5)
    seen = set()
    for _ in range(200):
        mates = np.zeros((4, 2), dtype=np.int64)
        _draw_mates(PAIRINGS.index("shuffle"), costs, order, 1, 4, 0, False, pop, lengths, rng,
                    mates)
        np.testing.assert_array_equal(mates[:3, 1], mates[1:, 0])  # a chain of 5 strings
        assert len(set(mates.ravel().tolist())) == 5
        seen.update(mates.ravel().tolist())
    assert seen == {0, 1, 2, 3, 4}  # the elite mates too


def test_double_pairing_draws_twice_as_many_distinct_pairs():
    rng = np.random.default_rng(2)
    costs = np.arange(5.0)
    pop, lengths = _population([[0, 1, 2]] * 5)
    mates = np.zeros((8, 2), dtype=np.int64)
    _draw_mates(PAIRINGS.index("double"), costs, np.arange(5), 1, 8, 0, False, pop, lengths,
                rng, mates)
    assert np.all(mates[:, 0] != mates[:, 1])
    assert np.all((mates >= 0) & (mates < 5))


@pytest.mark.parametrize("pairing", ["double", "shuffle", "rest"])
def test_distinct_mates_avoid_identical_strings_when_others_exist(pairing):
    rng = np.random.default_rng(3)
    # strings 0, 1, 2 are the same tour; 3 and 4 differ from them and from each other
    pop, lengths = _population([[0, 1, 2, 3], [0, 1, 2, 3], [0, 1, 2, 3], [0, 2, 1, 3],
                                [0, 3, 1, 2]])
    costs = np.array([1.0, 1.0, 1.0, 2.0, 3.0])
    identical = {0, 1, 2}
    for _ in range(100):
        mates = np.zeros((8, 2), dtype=np.int64)
        n_kids = 8 if pairing == "double" else 4
        _draw_mates(PAIRINGS.index(pairing), costs, np.arange(5), 1, n_kids, 0, True, pop,
                    lengths, rng, mates)
        for a, b in mates[:n_kids]:
            assert not (int(a) in identical and int(b) in identical)


def test_rotate_to_keeps_the_cycle_and_starts_at_the_city():
    out = np.empty(6, dtype=np.int64)
    _rotate_to(np.array([4, 2, 5, 0, 1, 3]), 6, 0, out)
    np.testing.assert_array_equal(out, [0, 1, 3, 4, 2, 5])


def test_edge_convergence_counts_differing_edges_and_adjacency_counts_direction():
    tour = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]
    reverse = tour[::-1]
    swapped = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]  # 2 of its 10 edges are not in the tour
    costs = np.array([1.0, 2.0, 2.0, 2.0])
    pop, lengths = _population([tour, reverse, tour, reverse])
    assert _edges_converged(pop, lengths, costs, 0.0, False)  # the same edges
    assert not _edges_converged(pop, lengths, costs, 0.5, True)  # 20 of 30 entries differ
    assert _edges_converged(pop, lengths, costs, 20 / 30, True)
    pop, lengths = _population([tour, swapped, tour, tour])
    assert not _edges_converged(pop, lengths, costs, 1 / 30, False)  # 2 of 30 differ
    assert _edges_converged(pop, lengths, costs, 2 / 30, False)


# --- the paper preset ----------------------------------------------------------------


def test_paper_preset_runs_the_paper_loop_and_only_it():
    assert SolverParams(preset="paper").paper_loop is None  # PAPER_LOOP applies
    assert PAPER_LOOP.population == 5 and PAPER_LOOP.elite == 1
    assert PAPER_LOOP.mutation_rate == 0.0 and PAPER_LOOP.restart_on_convergence
    with pytest.raises(ParameterError, match="paper_loop"):
        SolverParams(paper_loop=GAConfig())
    with pytest.raises(ParameterError, match="paper_loop"):
        SolverParams(preset="paper", paper_loop={"pairing": "rest"})


def test_the_paper_preset_runs_paper_loop_with_its_population():
    problem = MatrixProblem(_random_matrix(6, 12))
    stop = MaxGenerations(40)
    implicit = solve(problem, seed=2, params=SolverParams(preset="paper"), stop=stop)
    explicit = solve(problem, seed=2, params=SolverParams(preset="paper", paper_loop=PAPER_LOOP),
                     stop=stop)
    np.testing.assert_array_equal(implicit.history.mean_cost, explicit.history.mean_cost)
    seven = solve(problem, seed=2, params=SolverParams(preset="paper", population=7), stop=stop)
    same_seven = solve(problem, seed=2, stop=stop, params=SolverParams(
        preset="paper", paper_loop=GAConfig(**{**PAPER_LOOP.__dict__, "population": 7})))
    np.testing.assert_array_equal(seven.history.mean_cost, same_seven.history.mean_cost)
    assert not np.array_equal(seven.history.mean_cost, implicit.history.mean_cost)


def test_paper_loop_option_changes_the_search_and_is_reproducible():
    problem = MatrixProblem(_random_matrix(5, 14))
    stop = MaxGenerations(60)
    rest = SolverParams(preset="paper", paper_loop=GAConfig(pairing="rest"))
    a = solve(problem, seed=1, params=rest, stop=stop)
    b = solve(problem, seed=1, params=rest, stop=stop)
    plain = solve(problem, seed=1, params=SolverParams(preset="paper",
                                                       paper_loop=GAConfig()), stop=stop)
    np.testing.assert_array_equal(a.order, b.order)
    np.testing.assert_array_equal(a.history.best_cost, b.history.best_cost)
    assert not np.array_equal(a.history.mean_cost, plain.history.mean_cost)


@pytest.mark.parametrize("seed", range(4))
def test_paper_preset_finds_the_held_karp_optimum_of_a_small_instance(seed):
    m = _random_matrix(10 + seed, 9)
    optimum, _ = held_karp(m)
    r = solve(MatrixProblem(m), seed=seed, params=SolverParams(preset="paper"),
              stop=MaxGenerations(3000))
    assert r.total_time == pytest.approx(optimum, rel=1e-12)


# --- every optimum -------------------------------------------------------------------


def _brute_force_optima(m: np.ndarray, rtol: float = 1e-9) -> tuple[float, set]:
    n = m.shape[0]
    best, tours = np.inf, set()
    for rest in itertools.permutations(range(1, n)):
        if rest[0] > rest[-1]:  # each undirected tour once
            continue
        order = (0, *rest)
        cost = tour_length(m, np.array(order))
        if cost < best * (1 - rtol):
            best, tours = cost, {_edge_set(order)}
        elif cost <= best * (1 + rtol):
            tours.add(_edge_set(order))
    return best, tours


@pytest.mark.parametrize("matrix", [_euclid(_lattice(3, 3)), _euclid(_lattice(4, 2)),
                                    _random_matrix(7, 8)], ids=["lattice3x3", "lattice4x2",
                                                                "random8"])
def test_optimal_tours_match_brute_force(matrix):
    cost, expected = _brute_force_optima(matrix)
    found = optimal_tours(matrix)
    assert found.cost == pytest.approx(cost, rel=1e-12)
    assert {_edge_set(t) for t in found.tours} == expected
    assert len(found.tours) == len(expected)  # each tour listed once
    assert found.next_cost > cost * (1 + 1e-9)


def _grid_hamiltonian_cycles(cols: int, rows: int) -> set:
    """Every Hamiltonian cycle of the cols x rows grid graph (unit steps), by DFS."""
    n = cols * rows

    def neighbours(v):
        x, y = v % cols, v // cols
        for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            if 0 <= x + dx < cols and 0 <= y + dy < rows:
                yield (y + dy) * cols + x + dx

    cycles = set()
    path = [0]
    used = [False] * n
    used[0] = True

    def extend():
        v = path[-1]
        if len(path) == n:
            if 0 in neighbours(v):
                cycles.add(_edge_set(path))
            return
        for w in neighbours(v):
            if not used[w]:
                used[w] = True
                path.append(w)
                extend()
                path.pop()
                used[w] = False

    extend()
    return cycles


def test_the_optima_of_a_5x4_lattice_are_its_14_hamiltonian_cycles():
    # with unit spacing every tour has 20 legs of length >= 1, so the optimal tours are
    # exactly the cycles of unit steps: the grid graph's Hamiltonian cycles
    cycles = _grid_hamiltonian_cycles(5, 4)
    assert len(cycles) == 14
    m = _euclid(_lattice(5, 4))
    found = optimal_tours(m)
    assert found.cost == pytest.approx(20.0)
    assert {_edge_set(t) for t in found.tours} == cycles
    for t in found.tours:
        assert tour_length(m, t) == pytest.approx(20.0, rel=1e-12)
    _check_cut_excluded_resolves(m, found, found.tours[:2])


def test_optimal_tours_on_the_paper_model_of_square20(square20_paper_matrix):
    m = square20_paper_matrix
    found = optimal_tours(m)
    cost, _ = milp_optimum(m)
    assert found.cost == pytest.approx(cost, rel=1e-12)
    assert len({_edge_set(t) for t in found.tours}) == len(found.tours)  # distinct
    for t in found.tours:
        assert sorted(t.tolist()) == list(range(20))
        assert tour_length(m, t) == pytest.approx(cost, rel=1e-9)  # evaluated apart
    assert found.next_cost > cost * (1 + 1e-9)
    _check_cut_excluded_resolves(m, found, found.tours)


def _check_cut_excluded_resolves(m, found, tours):
    """Excluding one listed optimum by its cut leaves the other listed optima, or (a
    unique optimum) a strictly worse best: the list is complete and correct."""
    listed = {_edge_set(t) for t in found.tours}
    for t in tours:
        rest = optimal_tours(m, exclude=[t])
        if len(found.tours) > 1:
            assert rest.cost == pytest.approx(found.cost, rel=1e-12)
            assert {_edge_set(u) for u in rest.tours} == listed - {_edge_set(t)}
        else:
            assert rest.cost > found.cost * (1 + 1e-9)
            assert rest.cost == pytest.approx(found.next_cost, rel=1e-12)


@pytest.fixture(scope="module")
def square20_paper_matrix():
    from subtask_opt import builtin_case
    from subtask_opt.kinematics.planar import load_planar_arm

    arm = load_planar_arm("planar_2r")
    return PlanarProblem(builtin_case("square20", arm), arm, time_model="paper").matrix


def test_optimal_tours_validates_and_caps():
    m = _euclid(_lattice(5, 4))
    with pytest.raises(ParameterError, match="max_tours"):
        optimal_tours(m, max_tours=0)
    with pytest.raises(ParameterError, match="rtol"):
        optimal_tours(m, rtol=-1.0)
    with pytest.raises(SubtaskOptError, match="more than max_tours=3"):
        optimal_tours(m, max_tours=3)
    with pytest.raises(ParameterError, match="exclude"):
        optimal_tours(m, exclude=[np.arange(19)])


def test_optimal_tours_figure_has_a_labelled_panel_per_tour(tmp_path, square20_paper_matrix):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from subtask_opt import builtin_case
    from subtask_opt.kinematics.planar import load_planar_arm
    from subtask_opt.plotting.sequencing import optimal_tours_figure, save_optimal_tours_figure

    arm = load_planar_arm("planar_2r")
    problem = PlanarProblem(builtin_case("square20", arm), arm, time_model="paper")
    found = optimal_tours(problem.matrix)
    panels = [(problem, found.tours[0], "optimum"), (problem, np.arange(20), "input order")]
    fig = optimal_tours_figure(panels, title="square20 optima")
    axes = fig.get_axes()
    assert [ax.get_title() for ax in axes] == ["optimum", "input order"]
    for ax in axes:
        assert ax.get_xlabel() == "x [m]" and ax.get_ylabel() == "y [m]"
        assert ax.get_legend() is None  # one legend for the figure
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert len(labels) == len(set(labels)) and "subtask" in labels
    assert fig._suptitle.get_text() == "square20 optima"
    plt.close(fig)
    out = save_optimal_tours_figure(panels, tmp_path / "o.png", title="t")
    assert out.stat().st_size > 10_000
    with pytest.raises(ValueError, match="at least one panel"):
        optimal_tours_figure([], title="none")
