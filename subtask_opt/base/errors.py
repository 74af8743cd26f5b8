"""The one exception family of subtask_opt.

Every user mistake raises a subclass of :class:`SubtaskOptError` (itself a
``ValueError``) whose message names the bad value and what is allowed; the CLI
prints that message as one line and exits with code 2.
"""

from __future__ import annotations

import math

import numpy as np


class SubtaskOptError(ValueError):
    """Base class of every error caused by bad input."""


class ParameterError(SubtaskOptError):
    """A parameter (limit, rate, size, option) is out of its allowed range."""


class InputDataError(SubtaskOptError):
    """An input file or array (subtasks, map, world, image) is malformed."""


class UnreachableError(SubtaskOptError):
    """A point lies outside what the robot or the world allows."""


class NoPathError(SubtaskOptError):
    """No collision-free path exists between the requested points."""


class TimeLimitReached(SubtaskOptError):
    """A job's time limit ran out before it could answer (the CLI exits 1: the job ran)."""


def require_positive(owner: str, name: str, value: float) -> None:
    """Raise :class:`ParameterError` unless ``value`` is finite and > 0."""
    if not _is_finite_number(value) or value <= 0:
        raise ParameterError(f"{owner}.{name} must be a finite number > 0, got {value!r}")


def require_non_negative(owner: str, name: str, value: float) -> None:
    """Raise :class:`ParameterError` unless ``value`` is finite and >= 0."""
    if not _is_finite_number(value) or value < 0:
        raise ParameterError(f"{owner}.{name} must be a finite number >= 0, got {value!r}")


def require_in_range(owner: str, name: str, value: float, low: float, high: float) -> None:
    """Raise :class:`ParameterError` unless ``low <= value <= high``."""
    if not _is_finite_number(value) or not (low <= value <= high):
        raise ParameterError(f"{owner}.{name} must be in [{low}, {high}], got {value!r}")


MAX_INT = 2**62
"""The largest whole number any count, limit or seed may take (kernels use int64)."""


def require_int(owner: str, name: str, value: int, minimum: int,
                maximum: int = MAX_INT) -> None:
    """Raise :class:`ParameterError` unless ``value`` is an integer in [minimum, maximum]."""
    if (isinstance(value, bool) or not isinstance(value, (int, np.integer))
            or not minimum <= value <= maximum):
        raise ParameterError(
            f"{owner}.{name} must be an integer in [{minimum}, {maximum}], got {value!r}")


def _is_finite_number(value: object) -> bool:
    """A real int or float (numpy ones too), not bool, str or complex, and finite."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # an int too large for a float
        return False
