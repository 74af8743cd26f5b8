"""The one exception family of subtask_opt.

Every user mistake raises a subclass of :class:`SubtaskOptError` (itself a
``ValueError``) whose message names the bad value and what is allowed; the CLI
prints that message as one line and exits with code 2.
"""

from __future__ import annotations


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


def require_int(owner: str, name: str, value: int, minimum: int) -> None:
    """Raise :class:`ParameterError` unless ``value`` is an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise ParameterError(f"{owner}.{name} must be an integer >= {minimum}, got {value!r}")


def _is_finite_number(value: object) -> bool:
    if isinstance(value, bool):
        return False
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False
    return v == v and v not in (float("inf"), float("-inf"))
