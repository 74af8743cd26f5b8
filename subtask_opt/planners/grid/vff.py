"""Virtual force field (Borenstein & Koren 1989) as a local grid planner.

A simulated point robot drives through the grid (see :mod:`._local`),
sensing the blocked cells within a window into a certainty grid C. Every
certain cell in the window pushes it away with ``Fcr C / d^2`` (eq. 2.1-2.2),
the target pulls with ``Fct`` (eq. 2.3); the robot steers towards the
resultant at rate ``Ks (delta - theta)`` (eq. 2.4-2.6), limited to
``max_turn_deg`` per step. A failed run is a ``success=False``
:class:`PlanResult` with outcome ``collision``, ``stall`` or ``timeout``.

The parameter classes are called ``GridVFFParams``/``GridRobotParams`` so they
never clash with the sonar VFF of :mod:`subtask_opt.planners.reactive`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from subtask_opt.base.errors import require_positive
from subtask_opt.base.results import PlanResult
from subtask_opt.planners.base import register
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid._local import GridRobotParams, drive
from subtask_opt.planners.grid.world import GridWorld

__all__ = ["GridRobotParams", "GridVFFParams", "plan"]


@dataclass(frozen=True)
class GridVFFParams:
    """VFF force constants (eq. 2.1-2.6) and the robot.

    Attributes:
        f_cr: repulsive force constant Fcr.
        f_ct: attractive (target) force constant Fct.
        k_s: steering gain Ks (per step, applied to the signed angle error).
        robot: the simulated robot (:class:`GridRobotParams`).
    """

    f_cr: float = 0.05
    f_ct: float = 1.0
    k_s: float = 0.3
    robot: GridRobotParams = field(default_factory=GridRobotParams)

    def __post_init__(self) -> None:
        for name in ("f_cr", "f_ct", "k_s"):
            require_positive("GridVFFParams", name, getattr(self, name))

    def kernel(self) -> K.VFFKernelParams:
        return K.VFFKernelParams(float(self.f_cr), float(self.f_ct), float(self.k_s))


@register("grid", "vff", description="virtual force field: a simulated robot, local, may stall")
def plan(world: GridWorld, start: Any, goal: Any, *, params: GridVFFParams | None = None,
         seed: int | None = None, stop: Any = None) -> PlanResult:
    """Drive from ``start`` to ``goal`` with the virtual force field.

    Deterministic: ``seed`` and ``stop`` must be None (the run ends by
    ``robot.max_steps``). See :func:`._local.drive` for the result and the
    errors it raises.
    """
    params = params or GridVFFParams()
    return drive("vff", K.vff_run, world, start, goal, params.robot, params.kernel(),
                 seed=seed, stop=stop)
