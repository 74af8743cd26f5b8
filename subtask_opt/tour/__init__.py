"""Robot-free sequencing: tour problems, :func:`solve`, bounds, exact oracles, readers.

:class:`MatrixProblem` (visit every node), :class:`ClusteredProblem` (visit one node
of every cluster), :class:`GtspProblem` (one vertex of every set, sets of any size) and
:class:`LazyLegsProblem` (one node of every cluster from a home, legs a
:class:`LegVerifier` corrects lazily: what a serial arm compiles into),
:class:`TourConstraints` (closed or open, fixed ends, a home node, precedence),
:func:`solve` and its :class:`Result`; the Held-Karp bound (:mod:`.bound`), exact oracles
(:mod:`.exact`), the TSPLIB and GTSPLIB readers (:mod:`.tsplib`, :mod:`.gtsplib`), the
peers that know no robot (:mod:`.peers`) and the tour chromosomes of the GA
(:mod:`.permutation`, :mod:`.precedence`, :mod:`.clustered`).
"""

from subtask_opt.tour.constraints import TourConstraints
from subtask_opt.tour.lazy import LazyLegsProblem, LegVerifier
from subtask_opt.tour.problem import ClusteredProblem, GtspProblem, MatrixProblem
from subtask_opt.tour.solve import Result, SolverParams, solve

__all__ = ["ClusteredProblem", "GtspProblem", "LazyLegsProblem", "LegVerifier",
           "MatrixProblem", "Result", "SolverParams", "TourConstraints", "solve"]
