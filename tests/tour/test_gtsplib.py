"""The GTSPLIB / PCGLNS reader against hand-computed distances, malformed files, and the
clustered solve against brute force (one vertex of every set, precedence kept)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.tour.constraints import TourConstraints
from subtask_opt.tour.exact import agtsp_optimum, gtsp_set_optimum
from subtask_opt.tour.gtsplib import GtspInstance, parse_gtsplib, read_gtsplib, solve_gtsp
from subtask_opt.tour.problem import GtspProblem
from subtask_opt.tour.solve import solve
from tests.conftest import SHARED_DATA

GTSPLIB = SHARED_DATA / "gtsplib"
PCGTSP = SHARED_DATA / "pcgtsp"

# six vertices in three sets; the coordinates make every distance a textbook case
POINTS = [(0, 0), (3, 4), (1, 1), (10, 0), (0, 7), (6, 8)]
SETS = "1 1 2 -1\n2 3 4 -1\n3 5 6 -1\n"


def _coords_file(kind: str, points=POINTS) -> str:
    nodes = "".join(f"{i + 1} {x} {y}\n" for i, (x, y) in enumerate(points))
    return (f"NAME : t\nTYPE : GTSP\nDIMENSION : {len(points)}\nGTSP_SETS : 3\n"
            f"EDGE_WEIGHT_TYPE : {kind}\nNODE_COORD_SECTION\n{nodes}GTSP_SET_SECTION\n"
            f"{SETS}EOF\n")


def _euclid(p, q):
    return math.sqrt((p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2)


def test_euc_2d_rounds_to_nearest():
    w = parse_gtsplib(_coords_file("EUC_2D")).weights
    assert w[0, 1] == 5  # 3-4-5
    assert w[0, 2] == 1  # sqrt 2 = 1.414 -> 1
    assert w[1, 2] == 4  # sqrt 13 = 3.606 -> 4
    assert w[3, 5] == 9  # sqrt 80 = 8.944 -> 9
    assert w[4, 5] == 6  # sqrt 37 = 6.083 -> 6


def test_every_coordinate_rule_matches_the_tsplib_formula():
    for kind, rule in [
        ("EUC_2D", lambda d: math.floor(d + 0.5)),
        ("CEIL_2D", math.ceil),
        ("ATT", lambda d: (lambda r: (lambda t: t + 1 if t < r else t)(math.floor(r + 0.5)))(
            d / math.sqrt(10.0))),
    ]:
        w = parse_gtsplib(_coords_file(kind)).weights
        for i, j in itertools.permutations(range(len(POINTS)), 2):
            assert w[i, j] == rule(_euclid(POINTS[i], POINTS[j])), (kind, i, j)


def test_att_and_ceil_by_hand():
    att = parse_gtsplib(_coords_file("ATT")).weights
    assert att[0, 3] == 4  # r = sqrt(100 / 10) = 3.162, nint 3 < r -> 4
    assert att[0, 1] == 2  # r = sqrt(25 / 10) = 1.581, nint 2 >= r -> 2
    ceil = parse_gtsplib(_coords_file("CEIL_2D")).weights
    assert ceil[0, 2] == 2 and ceil[0, 1] == 5


def _geo(a, b):
    """TSPLIB's GEO rule, written out from the TSPLIB 95 document."""
    pi, rrr = 3.141592, 6378.388

    def rad(x):
        deg = int(x)
        return pi * (deg + 5.0 * (x - deg) / 3.0) / 180.0

    lat1, lon1, lat2, lon2 = rad(a[0]), rad(a[1]), rad(b[0]), rad(b[1])
    q1, q2, q3 = math.cos(lon1 - lon2), math.cos(lat1 - lat2), math.cos(lat1 + lat2)
    return int(rrr * math.acos(0.5 * ((1.0 + q1) * q2 - (1.0 - q1) * q3)) + 1.0)


def test_geo_matches_the_tsplib_formula():
    points = [(38.24, 20.42), (39.57, 26.15), (40.56, 25.32), (36.26, 23.12),
              (33.48, 10.54), (37.56, 12.19)]
    w = parse_gtsplib(_coords_file("GEO", points)).weights
    for i, j in itertools.permutations(range(len(points)), 2):
        assert w[i, j] == _geo(points[i], points[j])
    assert w[0, 1] == 509  # ulysses16 cities 1 and 2 (TSPLIB's own table)


MATRIX = np.array([[0, 3, 5, 9], [3, 0, 4, 7], [5, 4, 0, 2], [9, 7, 2, 0]])
EXPLICIT = {
    "FULL_MATRIX": "0 3 5 9\n3 0 4 7\n5 4 0 2\n9 7 2 0\n",
    "UPPER_ROW": "3 5 9\n4 7\n2\n",
    "LOWER_ROW": "3\n5 4\n9 7 2\n",
    "UPPER_DIAG_ROW": "0 3 5 9\n0 4 7\n0 2\n0\n",
    "LOWER_DIAG_ROW": "0\n3 0\n5 4 0\n9 7 2 0\n",
}


def _explicit_file(fmt: str, body: str, kind: str = "GTSP", sets: str = "1 1 -1\n2 2 -1\n"
                   "3 3 4 -1\n", extra: str = "") -> str:
    return (f"NAME : x\nTYPE : {kind}\nDIMENSION : 4\nGTSP_SETS : 3\nEDGE_WEIGHT_TYPE : "
            f"EXPLICIT\nEDGE_WEIGHT_FORMAT : {fmt}\nEDGE_WEIGHT_SECTION\n{body}"
            f"GTSP_SET_SECTION\n{sets}{extra}EOF\n")


@pytest.mark.parametrize("fmt", list(EXPLICIT))
def test_every_explicit_format_gives_the_matrix(fmt):
    g = parse_gtsplib(_explicit_file(fmt, EXPLICIT[fmt]))
    np.testing.assert_array_equal(g.weights, MATRIX)
    np.testing.assert_array_equal(g.sets, [0, 1, 2, 2])


def test_weights_may_wrap_across_lines():
    g = parse_gtsplib(_explicit_file("UPPER_ROW", "3 5\n9 4 7 2\n"))
    np.testing.assert_array_equal(g.weights, MATRIX)


def test_agtsp_keeps_the_asymmetric_matrix_and_a_colonless_keyword():
    body = "0 1 2 3\n4 0 5 6\n7 8 0 9\n1 2 3 0\n"
    text = _explicit_file("FULL_MATRIX", body, kind="AGTSP").replace("TYPE : AGTSP",
                                                                        "TYPE  AGTSP")
    g = parse_gtsplib(text)
    assert g.problem_type == "AGTSP"
    assert g.weights[0, 3] == 3 and g.weights[3, 0] == 1
    assert not g.problem().symmetric


def test_pcglns_ordering_start_and_forbidden_arcs():
    body = "0 0 0 0\n0 0 -1 6\n0 8 0 9\n0 2 3 0\n"
    extra = "GTSP_SET_ORDERING\n2 3 -1\nSTART_GROUP_SECTION\n1\n"
    g = parse_gtsplib(_explicit_file("FULL_MATRIX", body, kind="PCGLNS", extra=extra))
    assert g.precedence == ((1, 2),)
    assert g.start == 0
    assert math.isinf(g.weights[1, 2])
    assert g.constraints() == TourConstraints(start=0, precedence=((1, 2),))


BAD = [
    # (what changes in a good file, the line the message names, a phrase of it)
    (lambda t: t.replace("DIMENSION : 4", "DIMENSION : four"), 3, "whole number"),
    (lambda t: t.replace("TYPE : GTSP", "TYPE : TSP"), 2, "TYPE"),
    (lambda t: t.replace("0 4 7\n", "0 x 7\n"), 9, "expected a number"),
    (lambda t: t.replace("0 4 7\n", "0 4\n"), 11, "expected 10 weights"),
    (lambda t: t.replace("0 4 7\n", "0 -4 7\n"), 9, "edge weight"),
    (lambda t: t.replace("2 2 -1", "2 2 9 -1"), 14, "vertex in 1..4"),
    (lambda t: t.replace("2 2 -1", "2 1 -1"), 14, "vertex 1 is in set 1 and set 2"),
    (lambda t: t.replace("3 3 4 -1", "3 3 4"), 15, "-1 to close set 3"),
    (lambda t: t.replace("3 3 4 -1", "4 3 4 -1"), 15, "set id in 1..3"),
    (lambda t: t.replace("3 3 4 -1", "3 3 -1"), 15, "vertex 4 is in none"),
    (lambda t: t.replace("EDGE_WEIGHT_FORMAT : UPPER_DIAG_ROW", "EDGE_WEIGHT_FORMAT : X"), 7,
     "EDGE_WEIGHT_FORMAT"),
    (lambda t: t.replace("NAME : x", "NAME : x\nBOGUS : 1"), 2, "expected a keyword"),
    (lambda t: t.replace("EDGE_WEIGHT_TYPE : EXPLICIT", "EDGE_WEIGHT_TYPE : EUC_2D"), 5,
     "NODE_COORD_SECTION"),
]


@pytest.mark.parametrize("case", range(len(BAD)))
def test_malformed_files_name_the_line(case):
    change, line, phrase = BAD[case]
    good = _explicit_file("UPPER_DIAG_ROW", EXPLICIT["UPPER_DIAG_ROW"])
    parse_gtsplib(good)  # the unchanged file is fine
    with pytest.raises(InputDataError) as info:
        parse_gtsplib(change(good), source="f.gtsp")
    message = str(info.value)
    assert f"f.gtsp line {line}:" in message, message
    assert phrase in message, message


def test_an_asymmetric_matrix_under_type_gtsp_is_refused():
    with pytest.raises(InputDataError, match="symmetric"):
        parse_gtsplib(_explicit_file("FULL_MATRIX", "0 1 2 3\n4 0 5 6\n7 8 0 9\n1 2 3 0\n"))


def test_a_precedence_cycle_is_refused():
    extra = "GTSP_SET_ORDERING\n2 3 -1\n3 2 -1\n"
    with pytest.raises(InputDataError, match="cycles"):
        parse_gtsplib(_explicit_file("FULL_MATRIX", EXPLICIT["FULL_MATRIX"], kind="PCGLNS",
                                     extra=extra))


# --------------------------------------------------------------------------- oracles


def _brute_force(w, sets, start=None, pairs=()):
    """The cheapest closed tour through one vertex of every set, by enumeration."""
    n = int(sets.max()) + 1
    members = [np.flatnonzero(sets == k) for k in range(n)]
    best = math.inf
    first = 0 if start is None else start
    rest = [k for k in range(n) if k != first]
    for perm in itertools.permutations(rest):
        order = (first, *perm)
        pos = {s: i for i, s in enumerate(order)}
        if any(pos[a] > pos[b] for a, b in pairs):
            continue
        for choice in itertools.product(*(members[s] for s in order)):
            v = np.array(choice)
            best = min(best, float(w[v, np.roll(v, -1)].sum()))
    return best


def _random_instance(seed, n_sets=5, symmetric=True, forbid=0.0):
    rng = np.random.default_rng(seed)
    sizes = rng.integers(1, 4, n_sets)
    sets = np.repeat(np.arange(n_sets), sizes)
    rng.shuffle(sets)
    m = len(sets)
    if symmetric:
        pts = rng.integers(0, 100, (m, 2))
        w = np.floor(np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1)) + 0.5)
    else:
        w = rng.integers(1, 100, (m, m)).astype(float)
    if forbid:
        w[rng.random((m, m)) < forbid] = np.inf
    np.fill_diagonal(w, 0.0)
    return w, sets


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("symmetric", [True, False])
@pytest.mark.parametrize("lns_steps", [None, 0])
def test_solve_finds_the_brute_force_optimum(seed, symmetric, lns_steps):
    w, sets = _random_instance(seed, symmetric=symmetric)
    problem = GtspProblem(w, sets, lns_steps=lns_steps)
    result = solve(problem, seed=seed)
    tour = result.configurations[result.order]
    assert np.array_equal(np.sort(sets[tour]), np.arange(problem.size))
    assert problem.tour_cost(tour) == pytest.approx(result.total_time)
    assert result.total_time == pytest.approx(_brute_force(w, sets))


def test_solve_gtsp_searches_with_its_population_and_finds_the_optimum(monkeypatch):
    import importlib

    from subtask_opt.tour import gtsplib

    solve_module = importlib.import_module("subtask_opt.tour.solve")  # the package's
    # ``solve`` attribute is the function

    w, sets = _random_instance(3, n_sets=6)
    m = len(sets)
    body = "".join(" ".join(str(int(x)) for x in row) + "\n" for row in w)
    members = "".join(f"{k + 1} " + " ".join(str(v + 1) for v in np.flatnonzero(sets == k))
                      + " -1\n" for k in range(int(sets.max()) + 1))
    text = (f"NAME : r\nTYPE : GTSP\nDIMENSION : {m}\nGTSP_SETS : {int(sets.max()) + 1}\n"
            "EDGE_WEIGHT_TYPE : EXPLICIT\nEDGE_WEIGHT_FORMAT : FULL_MATRIX\n"
            f"EDGE_WEIGHT_SECTION\n{body}GTSP_SET_SECTION\n{members}EOF\n")
    seen = []
    real = solve_module.solve

    def spy(problem, **kwargs):
        seen.append(kwargs["params"])
        return real(problem, **kwargs)

    monkeypatch.setattr(solve_module, "solve", spy)
    solution = solve_gtsp(parse_gtsplib(text), time_limit=5.0, seed=1)
    assert [p.population for p in seen] == [gtsplib.GTSP_POPULATION]
    assert gtsplib.GTSP_POPULATION != solve_module.SolverParams().population
    assert solution.cost == pytest.approx(_brute_force(w, sets))


@pytest.mark.parametrize("seed", range(4))
def test_solve_with_precedence_keeps_it(seed):
    w, sets = _random_instance(seed + 10, n_sets=6, symmetric=False)
    pairs = ((1, 3), (4, 2), (1, 5))
    result = solve(GtspProblem(w, sets), seed=seed,
                   constraints=TourConstraints(start=0, precedence=pairs))
    order = list(result.order)
    assert order[0] == 0
    assert all(order.index(a) < order.index(b) for a, b in pairs)
    tour = result.configurations[result.order]
    assert result.total_time == pytest.approx(float(w[tour, np.roll(tour, -1)].sum()))
    # the pinned clustered kind chooses the vertices during the search: the optimum
    assert result.total_time == pytest.approx(_brute_force(w, sets, 0, pairs))


@pytest.mark.parametrize("seed", range(4))
def test_agtsp_optimum_matches_brute_force_with_forbidden_arcs(seed):
    w, sets = _random_instance(seed + 20, n_sets=5, symmetric=False, forbid=0.2)
    expected = _brute_force(w, sets)
    if math.isinf(expected):
        with pytest.raises(Exception, match="no tour"):
            agtsp_optimum(w, sets)
        return
    cost, order, nodes = agtsp_optimum(w, sets)
    assert cost == pytest.approx(expected)
    assert order[0] == 0 and sorted(order.tolist()) == list(range(5))
    assert float(w[nodes, np.roll(nodes, -1)].sum()) == pytest.approx(cost)


def test_gtsp_set_optimum_symmetric_matches_brute_force():
    w, sets = _random_instance(31, n_sets=6)
    cost, nodes = gtsp_set_optimum(GtspProblem(w, sets))
    assert cost == pytest.approx(_brute_force(w, sets))


def test_problem_refuses_bad_sets():
    w = np.zeros((4, 4))
    with pytest.raises(InputDataError, match="set 1 empty"):
        GtspProblem(w, np.array([0, 2, 2, 3]))
    with pytest.raises(InputDataError, match="must be 4 whole numbers"):
        GtspProblem(w, np.array([0, 1, 2]))
    with pytest.raises(ParameterError, match="one vertex of each"):
        GtspProblem(w, np.array([0, 1, 2, 2])).tour_cost([0, 2, 3])  # set 2 twice


# --------------------------------------------------------------------------- shared data


@pytest.mark.skipif(not GTSPLIB.is_dir(), reason="shared GTSPLIB data not present")
def test_every_shared_instance_reads_as_a_partition():
    for path in sorted(GTSPLIB.glob("*.gtsp")):
        g = read_gtsplib(path)
        sets_declared = int(path.read_text().split("GTSP_SETS")[1].split()[1].strip(": "))
        assert g.set_count == sets_declared
        assert np.bincount(g.sets).min() >= 1
        assert g.dimension == len(g.sets)
        assert g.name == path.stem


@pytest.mark.skipif(not PCGTSP.is_dir(), reason="shared PCGTSP data not present")
def test_pcgtsp_tour_keeps_the_file_rules():
    g = read_gtsplib(PCGTSP / "ESC12.pcglns")
    assert isinstance(g, GtspInstance) and g.start == 0 and g.precedence
    solution = solve_gtsp(g, time_limit=5.0, seed=1)
    tour = solution.tour
    # the rules checked from the file's text, not from the reader's sets
    text = (PCGTSP / "ESC12.pcglns").read_text()
    section = text.split("GTSP_SET_SECTION")[1].split("GTSP_SET_ORDERING")[0]
    owner = {}
    for line in section.strip().splitlines():
        ids = [int(t) for t in line.split()]
        for v in ids[1:-1]:
            owner[v] = ids[0]
    visited = [owner[int(v) + 1] for v in tour]
    assert sorted(visited) == sorted(set(owner.values()))
    ordering = text.split("GTSP_SET_ORDERING")[1].split("START_GROUP_SECTION")[0]
    for line in ordering.strip().splitlines():
        ids = [int(t) for t in line.split()]
        for b in ids[1:-1]:
            assert visited.index(ids[0]) < visited.index(b)
    assert visited[0] == int(text.split("START_GROUP_SECTION")[1].split()[0])
