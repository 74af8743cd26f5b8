"""Time models: every pair of subtasks -> a travel time (:func:`travel_times`)."""

from subtask_opt.arm.timing.models import TIME_MODELS, LegCheck, TimingResult, travel_times

__all__ = ["TIME_MODELS", "LegCheck", "TimingResult", "travel_times"]
