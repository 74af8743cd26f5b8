"""The TSPLIB reader: official rounding rules, published optima, malformed files, fuzz."""

from __future__ import annotations

import json
import os
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.tour.bound import lower_bound
from subtask_opt.tour.exact import held_karp, milp_optimum
from subtask_opt.tour.tsplib import (
    EDGE_WEIGHT_FORMATS,
    TspInstance,
    distance_matrix,
    parse_tsplib,
    read_tsplib,
    solve_tsp,
)
from tests.conftest import SHARED_DATA

FUZZ_EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "60"))  # the long runs (make fuzz)

# Public TSPLIB instances (Reinelt 1991) small enough for an exact check.
BURMA14 = """NAME: burma14
TYPE: TSP
COMMENT: 14-Staedte in Burma (Zaw Win)
DIMENSION: 14
EDGE_WEIGHT_TYPE: GEO
EDGE_WEIGHT_FORMAT: FUNCTION
DISPLAY_DATA_TYPE: COORD_DISPLAY
NODE_COORD_SECTION
   1  16.47       96.10
   2  16.47       94.44
   3  20.09       92.54
   4  22.39       93.37
   5  25.23       97.24
   6  22.00       96.05
   7  20.47       97.02
   8  17.20       96.29
   9  16.30       97.38
  10  14.05       98.12
  11  16.53       97.38
  12  21.52       95.59
  13  19.41       97.13
  14  20.09       94.55
EOF
"""
BURMA14_OPT = 3323

ULYSSES16 = """NAME: ulysses16.tsp
TYPE: TSP
COMMENT: Odyssey of Ulysses (Groetschel/Padberg)
DIMENSION: 16
EDGE_WEIGHT_TYPE: GEO
DISPLAY_DATA_TYPE: COORD_DISPLAY
NODE_COORD_SECTION
1 38.24 20.42
2 39.57 26.15
3 40.56 25.32
4 36.26 23.12
5 33.48 10.54
6 37.56 12.19
7 38.42 13.11
8 37.52 20.44
9 41.23 9.10
10 41.17 13.05
11 36.08 -5.21
12 38.47 15.13
13 38.15 15.35
14 37.51 15.17
15 35.49 14.32
16 39.36 19.56
EOF
"""
ULYSSES16_OPT = 6859

GR17 = """NAME: gr17
TYPE: TSP
COMMENT: 17-city problem (Groetschel)
DIMENSION: 17
EDGE_WEIGHT_TYPE: EXPLICIT
EDGE_WEIGHT_FORMAT: LOWER_DIAG_ROW
EDGE_WEIGHT_SECTION
 0 633 0 257 390 0 91 661 228 0 412 227
 169 383 0 150 488 112 120 267 0 80 572 196
 77 351 63 0 134 530 154 105 309 34 29 0
 259 555 372 175 338 264 232 249 0 505 289 262
 476 196 360 444 402 495 0 353 282 110 324 61
 208 292 250 352 154 0 324 638 437 240 421 329
 297 314 95 578 435 0 70 567 191 27 346 83
 47 68 189 439 287 254 0 211 466 74 182 243
 105 150 108 326 336 184 391 145 0 268 420 53
 239 199 123 207 165 383 240 140 448 202 57 0
 246 745 472 237 528 364 332 349 202 685 542 157
 289 426 483 0 121 518 142 84 297 35 29 36
 236 390 238 301 55 96 153 336 0
EOF
"""
GR17_OPT = 2085


@pytest.fixture(scope="module")
def tsplib_dir():
    path = SHARED_DATA / "tsplib"
    if not (path / "optima.json").is_file():
        pytest.skip(f"shared TSPLIB data not found at {path}")
    return path


@pytest.fixture(scope="module")
def optima(tsplib_dir):
    return json.loads((tsplib_dir / "optima.json").read_text())["optimum"]


def _coords_file(points, kind="EUC_2D", extra=""):
    lines = [f"{i + 1} {x!r} {y!r}" for i, (x, y) in enumerate(points)]
    return (f"NAME: t\nTYPE: TSP\nDIMENSION: {len(points)}\nEDGE_WEIGHT_TYPE: {kind}\n"
            f"{extra}NODE_COORD_SECTION\n" + "\n".join(lines) + "\nEOF\n")


def _explicit_file(matrix: np.ndarray, fmt: str, per_line: int = 7, kind: str = "TSP") -> str:
    n = matrix.shape[0]
    if fmt == "FULL_MATRIX":
        values = matrix.ravel()
    else:
        row = {"UPPER_COL": "LOWER_ROW", "LOWER_COL": "UPPER_ROW",
               "UPPER_DIAG_COL": "LOWER_DIAG_ROW", "LOWER_DIAG_COL": "UPPER_DIAG_ROW"}
        fmt_row = row.get(fmt, fmt)
        values = np.array([matrix[i, j] for i in range(n) for j in range(n)
                           if {"UPPER_ROW": j > i, "UPPER_DIAG_ROW": j >= i,
                               "LOWER_ROW": j < i, "LOWER_DIAG_ROW": j <= i}[fmt_row]])
    chunks = [" ".join(str(v) for v in values[k:k + per_line])
              for k in range(0, len(values), per_line)]
    return (f"NAME: x\nTYPE: {kind}\nDIMENSION: {n}\nEDGE_WEIGHT_TYPE: EXPLICIT\n"
            f"EDGE_WEIGHT_FORMAT: {fmt}\nEDGE_WEIGHT_SECTION\n" + "\n".join(chunks) + "\nEOF\n")


# --------------------------------------------------------------------- shared instances

@pytest.mark.parametrize("name", ["eil51", "berlin52", "eil76", "kroA100", "ch150", "a280",
                                  "pr1002"])
def test_shared_instances_read(tsplib_dir, optima, name):
    inst = read_tsplib(tsplib_dir / f"{name}.tsp")
    n = int(re.sub(r"\D", "", name))  # TSPLIB names end in the number of cities
    assert inst.name == name
    assert inst.dimension == n
    assert inst.matrix.shape == (n, n)
    assert inst.coordinates is not None and inst.coordinates.shape == (n, 2)
    assert inst.edge_weight_type == "EUC_2D"
    assert np.array_equal(inst.matrix, inst.matrix.T)
    assert lower_bound(inst.matrix, iterations=200) <= optima[name]


def test_hand_computed_distances(tsplib_dir):
    berlin = read_tsplib(tsplib_dir / "berlin52.tsp")
    # nodes 1 (565, 575) and 2 (25, 185): sqrt(540^2 + 390^2) = sqrt(443700) = 666.108
    assert berlin.matrix[0, 1] == 666
    eil = read_tsplib(tsplib_dir / "eil51.tsp")
    # nodes 1 (37, 52) and 2 (49, 49): sqrt(153) = 12.37
    assert eil.matrix[0, 1] == 12
    a280 = read_tsplib(tsplib_dir / "a280.tsp")
    # nodes 1 (288, 149) and 2 (288, 129)
    assert a280.matrix[0, 1] == 20
    assert berlin.comment == "52 locations in Berlin (Groetschel)"


@pytest.mark.parametrize("name", ["eil51", "berlin52", "eil76"])
def test_published_optimum_certified(tsplib_dir, optima, name):
    """An exact MILP over our distances reaches exactly the published optimum."""
    inst = read_tsplib(tsplib_dir / f"{name}.tsp")
    cost, order = milp_optimum(inst.matrix.astype(float))
    assert cost == optima[name]
    assert inst.tour_length(order) == optima[name]


@pytest.mark.bench
@pytest.mark.parametrize("name", ["kroA100"])
def test_published_optimum_certified_slow(tsplib_dir, optima, name):
    inst = read_tsplib(tsplib_dir / f"{name}.tsp")
    assert milp_optimum(inst.matrix.astype(float))[0] == optima[name]


@pytest.mark.parametrize("name", ["berlin52", "ch150"])
def test_solver_tour_never_beats_published_optimum(tsplib_dir, optima, name):
    inst = read_tsplib(tsplib_dir / f"{name}.tsp")
    sol = solve_tsp(inst, time_limit=1.0, seed=0)
    assert sol.length == inst.tour_length(sol.order)
    assert sol.lower_bound <= optima[name] <= sol.length
    assert sol.gap_bound == pytest.approx((sol.length - sol.lower_bound) / sol.lower_bound)


# --------------------------------------------------------------------- rounding rules

def test_geo_rule_reaches_published_optima():
    """GEO with (int) truncation of the degrees (burma14 has 16.53: nint would differ)
    and a negative longitude (ulysses16, -5.21)."""
    for text, opt in ((BURMA14, BURMA14_OPT), (ULYSSES16, ULYSSES16_OPT)):
        inst = parse_tsplib(text)
        assert inst.edge_weight_type == "GEO"
        assert milp_optimum(inst.matrix.astype(float))[0] == opt


def test_explicit_lower_diag_row_reaches_published_optimum():
    inst = parse_tsplib(GR17)
    assert inst.coordinates is None
    assert inst.matrix[1, 0] == inst.matrix[0, 1] == 633
    assert inst.matrix[16, 15] == 336
    assert milp_optimum(inst.matrix.astype(float))[0] == GR17_OPT


def test_euc_2d_rounds_halves_up():
    # nint(2.5) = 3 (Python's round would give 2), nint(0.5) = 1
    m = distance_matrix(np.array([[0.0, 0.0], [2.5, 0.0], [0.0, 0.5]]), "EUC_2D")
    assert m[0, 1] == 3 and m[0, 2] == 1
    # sqrt(2.5^2 + 0.5^2) = 2.5495 -> 3
    assert m[1, 2] == 3


def test_ceil_2d():
    m = distance_matrix(np.array([[0.0, 0.0], [3.0, 4.0], [1.0, 1.0]]), "CEIL_2D")
    assert m[0, 1] == 5  # exactly 5
    assert m[0, 2] == 2  # sqrt(2) = 1.414 -> 2
    assert m[1, 2] == 4  # sqrt(4 + 9) = 3.606 -> 4


def test_att_pseudo_euclidean():
    pts = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 30.0], [10.0, 30.0]])
    m = distance_matrix(pts, "ATT")
    assert m[0, 1] == 4   # r = sqrt(10) = 3.16, nint 3 < r -> 4
    assert m[0, 2] == 10  # r = sqrt(90) = 9.49, nint 9 < r -> 10
    assert m[0, 3] == 10  # r = sqrt(100) = 10 exactly -> 10
    assert m[1, 2] == 10  # r = sqrt((100 + 900) / 10) = 10


def test_geo_single_distance_by_hand():
    # two cities on the equator 1 degree of longitude apart: RRR * (PI / 180) = 111.32 -> 112
    m = distance_matrix(np.array([[0.0, 0.0], [0.0, 1.0], [0.0, 2.0]]), "GEO")
    assert m[0, 1] == 112
    # 0.30 means 30 minutes = half a degree: RRR * PI * 0.5 / 180 = 55.66 -> 56
    m = distance_matrix(np.array([[0.0, 0.0], [0.0, 0.30], [0.0, 2.0]]), "GEO")
    assert m[0, 1] == 56


# --------------------------------------------------------------------- explicit formats

@pytest.mark.parametrize("fmt", EDGE_WEIGHT_FORMATS)
def test_every_explicit_format_round_trips_gr17(fmt):
    matrix = parse_tsplib(GR17).matrix
    back = parse_tsplib(_explicit_file(matrix, fmt, per_line=5))
    np.testing.assert_array_equal(back.matrix, matrix)


@settings(max_examples=40, deadline=None)
@given(n=st.integers(3, 12), seed=st.integers(0, 2**32 - 1), per_line=st.integers(1, 30),
       fmt=st.sampled_from(EDGE_WEIGHT_FORMATS))
def test_explicit_formats_round_trip(n, seed, per_line, fmt):
    rng = np.random.default_rng(seed)
    upper = np.triu(rng.integers(0, 10**6, (n, n)), 1)
    matrix = upper + upper.T
    inst = parse_tsplib(_explicit_file(matrix, fmt, per_line))
    np.testing.assert_array_equal(inst.matrix, matrix)


def test_atsp_full_matrix_keeps_both_directions():
    m = np.array([[0, 1, 9], [5, 0, 2], [3, 7, 0]])
    inst = parse_tsplib(_explicit_file(m, "FULL_MATRIX", kind="ATSP"))
    assert inst.problem_type == "ATSP" and not inst.symmetric
    np.testing.assert_array_equal(inst.matrix, m)
    assert inst.tour_length(np.array([0, 1, 2])) == 1 + 2 + 3


def test_explicit_diagonal_sentinel_is_zeroed():
    m = np.array([[9999, 1, 2], [1, 9999, 3], [2, 3, 9999]])
    inst = parse_tsplib(_explicit_file(m, "FULL_MATRIX"))
    assert np.all(np.diag(inst.matrix) == 0)
    assert inst.matrix[0, 2] == 2


def test_header_variants_are_read():
    text = ("name:x\n  COMMENT : one\nCOMMENT: two\ntype : TSP\nDIMENSION:3\n"
            "EDGE_WEIGHT_TYPE :EUC_2D\n\nNODE_COORD_SECTION:\n 3 0 4\n1 0 0\n2 3 0\n")
    inst = parse_tsplib(text)  # no EOF, sections with a colon, nodes out of order
    assert inst.name == "x" and inst.comment == "one\ntwo"
    np.testing.assert_array_equal(inst.coordinates, [[0, 0], [3, 0], [0, 4]])
    assert inst.matrix[0, 1] == 3 and inst.matrix[1, 2] == 5


# --------------------------------------------------------------------- malformed files

GOOD = _coords_file([(0.0, 0.0), (3.0, 0.0), (0.0, 4.0)])


@pytest.mark.parametrize(("text", "pattern"), [
    (GOOD.replace("DIMENSION: 3\n", ""), "NODE_COORD_SECTION before DIMENSION"),
    ("NAME: x\nTYPE: TSP\nEDGE_WEIGHT_TYPE: EUC_2D\n", "DIMENSION is missing"),
    (GOOD.replace("DIMENSION: 3", "DIMENSION: three"), "line 3: DIMENSION must be a whole"),
    (GOOD.replace("DIMENSION: 3", "DIMENSION: 2"), "line 3: DIMENSION must be at least 3"),
    (GOOD.replace("DIMENSION: 3", "DIMENSION: 4"), "line 9: the section ends after 3 of 4"),
    (GOOD.replace("3 0.0 4.0\n", "3 0.0 4.0\n4 1.0 1.0\n"), "line 9: more than DIMENSION"),
    (GOOD.replace("2 3.0 0.0", "2 3.0 zero"), "line 7: coordinates must be numbers"),
    (GOOD.replace("2 3.0 0.0", "2 3.0 nan"), "line 7: coordinates must be finite"),
    (GOOD.replace("2 3.0 0.0", "2 3.0"), "line 7: expected 'index x y'"),
    (GOOD.replace("2 3.0 0.0", "1 3.0 0.0"), "line 7: node 1 is given twice"),
    (GOOD.replace("2 3.0 0.0", "7 3.0 0.0"), "line 7: node index 7 is outside 1..3"),
    (GOOD.replace("2 3.0 0.0", "x 3.0 0.0"), "line 7: node index must be a whole number"),
    (GOOD.replace("EUC_2D", "EUC_3D"), "line 4: EDGE_WEIGHT_TYPE must be one of"),
    (GOOD.replace("EDGE_WEIGHT_TYPE: EUC_2D\n", ""), "EDGE_WEIGHT_TYPE is missing"),
    (GOOD.replace("TYPE: TSP", "TYPE: CVRP"), "line 2: TYPE must be TSP or ATSP"),
    (GOOD.replace("NAME: t", "NAME: t\nNAME: u"), "line 2: NAME given twice"),
    (GOOD.replace("NAME: t", "FOO: bar"), "line 1: unknown keyword 'FOO'"),
    (GOOD.replace("NAME: t", "hello"), "line 1: expected 'KEYWORD : value'"),
    ("NAME: x\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: EUC_2D\nEOF\n", "needs a NODE_COORD_SECTION"),
    (_explicit_file(np.ones((3, 3), int), "FULL_MATRIX").replace("1 1 1 1 1 1 1", "1 1 1 1 1"),
     "line 9: EDGE_WEIGHT_SECTION .*holds 7 weights; FULL_MATRIX with DIMENSION 3 needs 9"),
    (_explicit_file(np.ones((3, 3), int), "UPPER_ROW").replace("1 1 1", "1 1 1 1"),
     "line 7: more weights than UPPER_ROW"),
    (_explicit_file(np.ones((3, 3), int), "UPPER_ROW").replace("1 1 1", "1 1 1\n1"),
     "line 8: more weights than UPPER_ROW"),
    (_explicit_file(np.ones((3, 3), int), "UPPER_ROW").replace("1 1 1", "1 -1 1"),
     "line 7: edge weight must be in"),
    (_explicit_file(np.ones((3, 3), int), "UPPER_ROW").replace("1 1 1", "1 1.5 1"),
     "line 7: edge weight must be a whole number"),
    (_explicit_file(np.ones((3, 3), int), "UPPER_ROW").replace("1 1 1", "1 a 1"),
     "line 7: edge weight must be a number"),
    (_explicit_file(np.ones((3, 3), int), "UPPER_ROW").replace("EDGE_WEIGHT_FORMAT: UPPER_ROW\n",
                                                               ""),
     "line 5: EDGE_WEIGHT_SECTION needs EDGE_WEIGHT_FORMAT"),
    (_explicit_file(np.array([[0, 1, 2], [3, 0, 4], [5, 6, 0]]), "FULL_MATRIX"),
     "line 6: TYPE TSP but the matrix is not symmetric: weight 1 -> 2 is 1, 2 -> 1 is 3"),
    (_explicit_file(np.ones((3, 3), int), "UPPER_ROW", kind="ATSP"),
     "line 5: an ATSP needs EDGE_WEIGHT_FORMAT FULL_MATRIX"),
    (GOOD.replace("TYPE: TSP", "TYPE: ATSP"), "an ATSP needs explicit weights"),
    (GOOD.replace("NODE_COORD_SECTION", "TOUR_SECTION"), "line 5: TOUR_SECTION belongs"),
    (GOOD.replace("EOF", "FIXED_EDGES_SECTION\n1 2"), "FIXED_EDGES_SECTION is not closed"),
    (GOOD.replace("2 3.0 0.0", "2 1e300 0.0").replace("3 0.0 4.0", "3 -1e300 0.0"),
     "distances exceed"),
])
def test_malformed_files_are_refused(text, pattern):
    with pytest.raises(InputDataError, match=pattern):
        parse_tsplib(text, source="f.tsp")


def test_dimension_limit_comes_from_memory():
    text = GOOD.replace("DIMENSION: 3", "DIMENSION: 1000")
    with pytest.raises(InputDataError, match=r"line 3: DIMENSION 1000 is over the limit of 353 "
                                             r"cities \(the dense distance matrix needs 8000000"):
        parse_tsplib(text, max_matrix_bytes=10**6)  # isqrt(10**6 / 8) = 353
    huge = GOOD.replace("DIMENSION: 3", "DIMENSION: 100000000")
    with pytest.raises(InputDataError, match="over the limit of 11585"):
        parse_tsplib(huge)


def test_file_limits(tmp_path):
    path = tmp_path / "a.tsp"
    path.write_text(GOOD)
    assert read_tsplib(path).dimension == 3
    with pytest.raises(InputDataError, match=r"a.tsp has \d+ bytes; the limit is 10"):
        read_tsplib(path, max_file_bytes=10)
    binary = tmp_path / "b.tsp"
    binary.write_bytes(b"NAME: \xff\xfe\n")
    with pytest.raises(InputDataError, match="not a text file"):
        read_tsplib(binary)
    with pytest.raises(InputDataError, match="not found"):  # one line, never an OSError
        read_tsplib(tmp_path / "missing.tsp")


def test_instance_validation():
    m = np.array([[0, 1, 2], [1, 0, 3], [2, 3, 0]], dtype=np.int64)
    with pytest.raises(ParameterError, match="dimension"):
        TspInstance("x", 2, "EUC_2D", None, m[:2, :2])
    with pytest.raises(ParameterError, match="edge_weight_type"):
        TspInstance("x", 3, "EUC_3D", None, m)
    with pytest.raises(ParameterError, match="int64"):
        TspInstance("x", 3, "EXPLICIT", None, m.astype(float))
    with pytest.raises(ParameterError, match="symmetric"):
        TspInstance("x", 3, "EXPLICIT", None, np.triu(m))
    with pytest.raises(ParameterError, match="coordinates"):
        TspInstance("x", 3, "EUC_2D", np.zeros((2, 2)), m)
    inst = TspInstance("x", 3, "EXPLICIT", None, m)
    assert not inst.matrix.flags.writeable
    with pytest.raises(ParameterError, match="permutation"):
        inst.tour_length(np.array([0, 0, 1]))


def test_solve_tsp_validates():
    inst = parse_tsplib(GR17)
    with pytest.raises(ParameterError, match="time_limit"):
        solve_tsp(inst, time_limit=0)
    with pytest.raises(ParameterError, match="seed"):
        solve_tsp(inst, seed=-1)
    with pytest.raises(ParameterError, match="TspInstance"):
        solve_tsp(inst.matrix)  # type: ignore[arg-type]


@pytest.mark.parametrize("seed", range(2))
def test_solve_tsp_on_an_atsp_brackets_the_held_karp_optimum(seed):
    rng = np.random.default_rng(seed)
    m = rng.integers(1, 100, (9, 9))
    np.fill_diagonal(m, 0)
    inst = parse_tsplib(_explicit_file(m, "FULL_MATRIX", kind="ATSP"))
    opt, _ = held_karp(m.astype(float))
    sol = solve_tsp(inst, time_limit=2.0, seed=seed)
    assert sol.lower_bound <= opt <= sol.length
    assert sol.length == inst.tour_length(sol.order)


def test_solve_tsp_brackets_gr17_optimum_and_is_reproducible():
    inst = parse_tsplib(GR17)
    a = solve_tsp(inst, time_limit=5.0, seed=4)
    b = solve_tsp(inst, time_limit=5.0, seed=4)
    assert np.array_equal(a.order, b.order) and a.length == b.length
    assert a.lower_bound <= GR17_OPT <= a.length
    payload = a.to_dict()
    assert payload["tour"] == [i + 1 for i in payload["order"]]
    json.dumps(payload)


# --------------------------------------------------------------------- fuzz

_KEYWORDS = ["NAME: x", "TYPE: TSP", "TYPE: ATSP", "DIMENSION: 3", "DIMENSION: 4",
             "DIMENSION: -1", "EDGE_WEIGHT_TYPE: EUC_2D", "EDGE_WEIGHT_TYPE: GEO",
             "EDGE_WEIGHT_TYPE: EXPLICIT", "EDGE_WEIGHT_FORMAT: FULL_MATRIX",
             "EDGE_WEIGHT_FORMAT: UPPER_ROW", "NODE_COORD_SECTION", "EDGE_WEIGHT_SECTION",
             "DISPLAY_DATA_SECTION", "FIXED_EDGES_SECTION", "EOF", "1 0 0", "2 3 0", "3 0 4",
             "4 1 1", "1 2 3", "0 1 2 3 4 5", "-1", "1e999 2 3", ":", "COMMENT: :"]


def _check_parsed(text: str) -> None:
    try:
        inst = parse_tsplib(text, max_matrix_bytes=8 * 200 * 200)
    except InputDataError:
        return
    n = inst.dimension
    assert inst.matrix.shape == (n, n) and inst.matrix.dtype == np.int64
    assert np.all(inst.matrix >= 0) and np.all(np.diag(inst.matrix) == 0)
    if inst.symmetric:
        assert np.array_equal(inst.matrix, inst.matrix.T)


_TEXT = st.text(max_size=400)
_SOUP = st.lists(st.one_of(st.sampled_from(_KEYWORDS), st.text(max_size=20)), max_size=25)


def _mutated(data) -> str:
    base = data.draw(st.sampled_from([GOOD, GR17, BURMA14]))
    lines = base.splitlines()
    for _ in range(data.draw(st.integers(1, 4))):
        i = data.draw(st.integers(0, len(lines) - 1))
        action = data.draw(st.sampled_from(["drop", "dup", "edit"]))
        if action == "drop" and len(lines) > 1:
            lines.pop(i)
        elif action == "dup":
            lines.insert(i, lines[i])
        else:
            lines[i] = data.draw(st.text(max_size=30))
    return "\n".join(lines)


def _short(test):
    return settings(max_examples=40, deadline=None)(test)


def _long(test):
    return pytest.mark.fuzz(settings(max_examples=FUZZ_EXAMPLES, deadline=None,
                                     suppress_health_check=[HealthCheck.too_slow])(test))


@_short
@given(_TEXT)
def test_fuzz_arbitrary_text(text):
    _check_parsed(text)


@_long
@given(_TEXT)
def test_fuzz_arbitrary_text_long(text):
    _check_parsed(text)


@_short
@given(_SOUP)
def test_fuzz_keyword_soup(lines):
    _check_parsed("\n".join(lines))


@_long
@given(_SOUP)
def test_fuzz_keyword_soup_long(lines):
    _check_parsed("\n".join(lines))


@_short
@given(st.data())
def test_fuzz_mutated_valid_files(data):
    _check_parsed(_mutated(data))


@_long
@given(st.data())
def test_fuzz_mutated_valid_files_long(data):
    _check_parsed(_mutated(data))
