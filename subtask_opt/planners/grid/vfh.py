"""Vector field histogram (Borenstein & Koren 1991) as a local grid planner.

Each step the cells of the active window (a certainty grid filled by a
simulated sensor) vote into a polar histogram of ``n = 360 / alpha`` sectors
with magnitude ``m = C^2 (a - b d)`` (eq. 2.7-2.10), smoothed by eq. 2.11.
Sectors below ``threshold`` form valleys; the robot steers at the target if
its sector lies in a wide valley, else at the middle of the nearest valley (up
to ``s_max`` sectors wide). Runs end as for :mod:`.vff` (see :mod:`._local`).

Smoothing, eq. 2.11. The thesis prints
``h'_k = (h_{k-l} + 2 h_{k-l+1} + ... + l h_k + ... + 2 h_{k+l-1} + h_{k+l}) / (2l + 1)``.
The printed sequence 1, 2, ... climbs by one per sector, which puts ``l + 1``
on the centre sector after ``l`` sectors, while the centre term is printed as
``l h_k``. ``GridVFHParams.centre_weight`` picks the reading:
``"printed"`` (default) weights the centre ``l`` as printed and every other
sector as in the sequence (``l + 1 - |i|``); ``"sequence"`` weights the centre
``l + 1`` (Borenstein & Koren's triangle 1..l+1..1). Both divide by ``2l + 1``
as printed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from subtask_opt.base.errors import ParameterError, require_int, require_positive
from subtask_opt.base.results import PlanResult
from subtask_opt.planners.base import register
from subtask_opt.planners.grid import _kernels as K
from subtask_opt.planners.grid._local import GridRobotParams, drive
from subtask_opt.planners.grid.world import GridWorld

__all__ = ["CENTRE_WEIGHTS", "GridVFHParams", "plan"]

CENTRE_WEIGHTS = ("printed", "sequence")


@dataclass(frozen=True)
class GridVFHParams:
    """VFH histogram and steering parameters (eq. 2.7-2.11) and the robot.

    Attributes:
        alpha_deg: sector width alpha; ``360 / alpha_deg`` must be a whole number >= 4.
        a, b: magnitude ``m = C^2 (a - b d)``; ``b = None`` picks
            ``a / (window * sqrt(2))`` so that ``m`` falls to 0 at the window corner.
        smoothing: ``l`` of eq. 2.11.
        centre_weight: ``"printed"`` (centre weight ``l``, the thesis' print)
            or ``"sequence"`` (``l + 1``); see the module docstring.
        threshold: smoothed density below which a sector is free.
        s_max: sectors of a wide valley.
        robot: the simulated robot (:class:`GridRobotParams`; slower than VFF's
            by default, 0.1 cell per step, which keeps VFH out of collisions in
            tight maps).
    """

    alpha_deg: float = 10.0
    a: float = 1.0
    b: float | None = None
    smoothing: int = 2
    centre_weight: str = "printed"
    threshold: float = 10.0
    s_max: int = 8
    robot: GridRobotParams = field(default_factory=lambda: GridRobotParams(speed=0.1))

    def __post_init__(self) -> None:
        o = "GridVFHParams"
        require_positive(o, "alpha_deg", self.alpha_deg)
        n = 360.0 / self.alpha_deg
        if abs(n - round(n)) > 1e-9 or round(n) < 4:
            raise ParameterError(
                f"{o}.alpha_deg must divide 360 into at least 4 sectors, got {self.alpha_deg!r}")
        require_positive(o, "a", self.a)
        if self.b is not None:
            require_positive(o, "b", self.b)
        require_int(o, "smoothing", self.smoothing, 0, 1000)
        if self.centre_weight not in CENTRE_WEIGHTS:
            raise ParameterError(f"{o}.centre_weight must be one of {CENTRE_WEIGHTS}, "
                                 f"got {self.centre_weight!r}")
        require_positive(o, "threshold", self.threshold)
        require_int(o, "s_max", self.s_max, 1, 1000)

    @property
    def b_value(self) -> float:
        return self.b if self.b is not None else self.a / (self.robot.window * math.sqrt(2.0))

    @property
    def centre(self) -> float:
        """The weight of the centre sector in eq. 2.11."""
        extra = 1 if self.centre_weight == "sequence" else 0
        return float(self.smoothing + extra) if self.smoothing > 0 else 1.0

    def kernel(self) -> K.VFHKernelParams:
        return K.VFHKernelParams(math.radians(self.alpha_deg), float(self.a),
                                 float(self.b_value), int(self.smoothing), self.centre,
                                 float(self.threshold), int(self.s_max))


@register("grid", "vfh", description="vector field histogram: a simulated robot, local, may stall")
def plan(world: GridWorld, start: Any, goal: Any, *, params: GridVFHParams | None = None,
         seed: int | None = None, stop: Any = None) -> PlanResult:
    """Drive from ``start`` to ``goal`` with the vector field histogram.

    Deterministic, as :mod:`.vff`: the result and the errors are those of
    :func:`._local.drive`.
    """
    params = params or GridVFHParams()
    return drive("vfh", K.vfh_run, world, start, goal, params.robot, params.kernel(),
                 seed=seed, stop=stop)
