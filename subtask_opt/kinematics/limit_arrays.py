"""Validation of per-joint limit arrays, shared by the planar arm's
:class:`~subtask_opt.kinematics.planar.JointLimits` and the serial arm's
:class:`~subtask_opt.kinematics.serial.SerialLimits`."""

from __future__ import annotations

from typing import Any

import numpy as np

from subtask_opt.base.errors import ParameterError

LIMIT_RANGE = (1e-6, 1e6)
"""Speed, acceleration and jerk limits (Cartesian and joint) lie in this range: outside it a
time model's arithmetic under- or overflows."""
POSITION_BOUND = 1e3
"""Position limits must lie within +- this (rad, or m for prismatic joints)."""
FIELDS = ("lower", "upper", "velocity", "acceleration", "jerk")


def freeze_limit_arrays(limits: Any, optional: tuple[str, ...], joints: int | None = None) -> None:
    """Validate the :data:`FIELDS` of the frozen dataclass ``limits`` and store them as
    read-only float64 arrays of one length (``joints`` if given, else the first field's).

    Fields named in ``optional`` may be None. Raises ParameterError naming the class,
    the field and the allowed values.
    """
    owner = type(limits).__name__
    n = joints
    for field in FIELDS:
        value = getattr(limits, field)
        if value is None:
            if field in optional:
                continue
            raise ParameterError(f"{owner}.{field} is required, got None")
        try:
            arr = np.array(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise ParameterError(
                f"{owner}.{field} must be a list of numbers, got {value!r}") from None
        if arr.ndim != 1 or arr.size == 0:
            raise ParameterError(f"{owner}.{field} must be a non-empty 1-D list, got {value!r}")
        n = arr.size if n is None else n
        if arr.size != n:
            raise ParameterError(
                f"{owner}.{field} must have {n} values (one per joint), got {value!r}")
        if not np.all(np.isfinite(arr)):
            raise ParameterError(f"{owner}.{field} must be finite, got {arr.tolist()}")
        if field in ("lower", "upper"):
            if np.any(np.abs(arr) > POSITION_BOUND):
                raise ParameterError(f"{owner}.{field} must be within +-{POSITION_BOUND:g}, "
                                     f"got {arr.tolist()}")
        elif np.any((arr < LIMIT_RANGE[0]) | (arr > LIMIT_RANGE[1])):
            raise ParameterError(f"{owner}.{field} must be in [{LIMIT_RANGE[0]:g}, "
                                 f"{LIMIT_RANGE[1]:g}], got {arr.tolist()}")
        arr.setflags(write=False)
        object.__setattr__(limits, field, arr)
    if np.any(limits.lower >= limits.upper):
        raise ParameterError(f"{owner}.lower must be < upper, got lower={limits.lower.tolist()} "
                             f"upper={limits.upper.tolist()}")
