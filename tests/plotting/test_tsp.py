"""The TSPLIB tour figure: labels, legend, title, and a refusal without coordinates."""

from __future__ import annotations

import numpy as np
import pytest

from subtask_opt.plotting.tsp import plot_tour, save_tour_figure
from subtask_opt.tour.tsplib import TspSolution, parse_tsplib
from tests.tour.test_tsplib import BURMA14, GR17


def _solution(n: int) -> TspSolution:
    return TspSolution(name="x", order=np.arange(n), length=10, lower_bound=9.0,
                       gap_bound=1 / 9, runtime_s=0.1, bound_runtime_s=0.01, seed=0,
                       generations=3)


def test_geo_tour_figure(tmp_path):
    import matplotlib.pyplot as plt

    inst = parse_tsplib(BURMA14)
    ax = plot_tour(inst, _solution(14))
    assert ax.get_xlabel() == "longitude [DDD.MM]" and ax.get_ylabel() == "latitude [DDD.MM]"
    assert "burma14" in ax.get_title() and ax.get_legend() is not None
    line = ax.get_lines()[0]
    np.testing.assert_allclose(line.get_xdata()[:2], inst.coordinates[:2, 1])  # longitude across
    assert len(line.get_xdata()) == 15  # closed
    plt.close("all")
    out = save_tour_figure(inst, _solution(14), tmp_path / "t.png")
    assert out.stat().st_size > 10_000


def test_no_coordinates_is_refused():
    with pytest.raises(ValueError, match="no node coordinates"):
        plot_tour(parse_tsplib(GR17), _solution(17))
