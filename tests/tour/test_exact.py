"""Exact TSP oracles against brute force."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from subtask_opt.base.errors import ParameterError
from subtask_opt.tour.exact import held_karp, milp_optimum, tour_length


def _brute_force(m: np.ndarray) -> float:
    n = m.shape[0]
    return min(tour_length(m, (0,) + p) for p in itertools.permutations(range(1, n)))


@pytest.mark.parametrize("seed", range(6))
def test_held_karp_equals_brute_force(seed):
    rng = np.random.default_rng(seed)
    n = 4 + seed % 4
    m = rng.random((n, n)) * 10  # asymmetric on purpose
    np.fill_diagonal(m, 0)
    cost, order = held_karp(m)
    assert cost == pytest.approx(_brute_force(m))
    assert tour_length(m, order) == pytest.approx(cost)
    assert sorted(order) == list(range(n))


@pytest.mark.parametrize("seed", range(4))
def test_milp_equals_held_karp_on_symmetric_instances(seed):
    pts = np.random.default_rng(seed).random((11, 2))
    m = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))
    cost, order = milp_optimum(m)
    assert cost == pytest.approx(held_karp(m)[0])
    assert tour_length(m, order) == pytest.approx(cost)


def test_bad_inputs():
    with pytest.raises(ParameterError, match="square"):
        held_karp(np.zeros((3, 4)))
    with pytest.raises(ParameterError, match="at most 16"):
        held_karp(np.ones((17, 17)))
    with pytest.raises(ParameterError, match="symmetric"):
        milp_optimum(np.arange(16, dtype=float).reshape(4, 4))
    with pytest.raises(ParameterError, match="finite"):
        milp_optimum(np.full((4, 4), np.nan))
