"""Every chromosome kind of the package and the module that defines its operators.

The one place where kinds are registered with the GA's dispatch
(:func:`subtask_opt.ga.dispatch.register`): a caller asks for the kind it runs,
``run_ga(use(Kind.PERMUTATION), ...)``, and :func:`use` imports the defining module
and registers its ``OPERATORS`` then. Importing a kernel module registers nothing, and
:mod:`subtask_opt.ga` imports no tour, robot or map.
"""

from __future__ import annotations

import importlib
import threading

from subtask_opt.base.errors import ParameterError
from subtask_opt.ga import dispatch
from subtask_opt.ga.kinds import Kind

SOURCES: dict[Kind, str] = {
    Kind.PERMUTATION: "subtask_opt.tour.permutation",
    Kind.CONFIGURED_PERMUTATION: "subtask_opt.tour.clustered",
    Kind.WAYPOINT_PATH: "subtask_opt.planners.grid._waypoint_kernels",
    Kind.PINNED_PERMUTATION: "subtask_opt.tour.precedence",
    Kind.PINNED_CLUSTERED: "subtask_opt.tour.pinned_clustered",
}
"""Kind -> the module whose ``OPERATORS`` (an :class:`~subtask_opt.ga.dispatch.OperatorSet`)
are that kind's five operators."""

_LOCK = threading.Lock()


def use(kind: Kind) -> Kind:
    """Register ``kind``'s operators (once) and return ``kind``, for :func:`run_ga`."""
    if not isinstance(kind, Kind) or kind not in SOURCES:
        raise ParameterError(f"use: kind must be one of {[k.name for k in SOURCES]}, "
                             f"got {kind!r}")
    with _LOCK:
        if dispatch.registered(kind) is None:
            module = importlib.import_module(SOURCES[kind])
            dispatch.register(kind, module.OPERATORS)
    return kind
