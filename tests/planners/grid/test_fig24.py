"""The thesis' Fig. 2.4: its printed 3:4 distance field, value by value.

The values below are typed from the thesis (seed 000, Fig. 2.4); ``None`` is
an obstacle cell. The thesis' transform lets a diagonal step pass one blocked
corner (e.g. 38 at (0, 1) = 34 + 4 past the obstacle corner), which is why the
chamfer planner cuts corners by default.
"""

from __future__ import annotations

import numpy as np
import pytest

from subtask_opt.planners.grid import distance_transform as dt
from subtask_opt.planners.grid.maps import thesis_case

X = None
PRINTED = [
    [37, 34, 31, 28, 25, 22, 19, 16, 13, 10, 7, 4, 3, 4],
    [38, X, X, X, X, 21, 18, 15, 12, 9, 6, 3, 0, 3],
    [41, X, X, X, X, 22, 19, 16, 13, 10, 7, 4, 3, 4],
    [40, X, X, X, X, 23, 20, 17, 14, 11, 8, 7, 6, 7],
    [39, 36, 33, 30, 27, 24, 21, 18, 15, 12, 11, 10, 9, 10],
    [40, 37, 34, 31, 28, 25, 22, 19, 16, X, X, X, X, X],
    [41, 38, 35, 32, 29, 26, 23, 20, 19, X, X, X, X, X],
    [42, 39, 36, 33, 30, 27, 24, 23, 22, X, X, X, X, X],
    [43, 40, 37, 34, 31, 28, 27, 26, 25, X, X, X, X, X],
]


def test_map_matches_the_figure():
    case = thesis_case("fig2.4")
    assert (case.world.width, case.world.height) == (14, 9) and case.border == 0
    assert case.start == (2, 7) and case.goal == (12, 1)
    blocked = np.array([[v is None for v in row] for row in PRINTED])
    assert np.array_equal(case.world.occupancy, blocked)


@pytest.mark.parametrize("y", range(9))
def test_every_printed_value(y):
    case = thesis_case("fig2.4")
    field = dt.distance_field(case.world, case.goal, "chamfer34") * 3
    for x, printed in enumerate(PRINTED[y]):
        if printed is None:
            assert field[y, x] == np.inf
        else:
            assert field[y, x] == printed, (x, y)


def test_without_corner_cutting_the_figure_differs():
    case = thesis_case("fig2.4")
    field = dt.distance_field(case.world, case.goal, "chamfer34", corner_cutting=False) * 3
    # (0, 1) can no longer take the diagonal past the obstacle corner at (1, 1)
    assert field[1, 0] == PRINTED[0][0] + 3
    # (0, 3) loses the diagonal from (1, 4) past (1, 3) and comes from (0, 4) instead
    assert field[3, 0] == field[4, 0] + 3 > PRINTED[3][0]
