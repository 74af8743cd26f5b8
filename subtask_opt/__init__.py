"""subtask_opt: minimum-time subtask sequencing for a planar arm, and mobile-robot planners.

The sequencing API::

    from subtask_opt import load_arm, builtin_case, SequencingProblem, solve
    arm = load_arm("planar_2r")
    problem = SequencingProblem(builtin_case("random30", arm, seed=0), arm)
    result = solve(problem, seed=1)
    print(result.summary())

Planners live in :mod:`subtask_opt.planners`; figures in :mod:`subtask_opt.plotting`.
"""

from .arm import ROBOT_NAMES, Arm, CartesianLimits, JointLimits, load_arm
from .configurations import best_configurations
from .errors import (
    InputDataError,
    NoPathError,
    ParameterError,
    SubtaskOptError,
    UnreachableError,
)
from .exact import held_karp, milp_optimum
from .result import History, PlanResult
from .sequencing import PRESETS, Result, SequencingProblem, SolverParams, solve
from .stop import MaxGenerations, MaxRuntime, NoImprovement, TargetCost
from .tasks import CASE_NAMES, SubtaskSet, builtin_case, load_subtasks, save_subtasks
from .timing import TIME_MODELS, LegCheck, TimingResult, travel_times
from .trajectory import TourTrajectory, tour_trajectory, validate_trajectory

__version__ = "0.1.0"

__all__ = [
    "Arm", "CartesianLimits", "JointLimits", "load_arm", "ROBOT_NAMES",
    "SubtaskSet", "builtin_case", "load_subtasks", "save_subtasks", "CASE_NAMES",
    "TIME_MODELS", "LegCheck", "TimingResult", "travel_times",
    "SequencingProblem", "SolverParams", "Result", "solve", "PRESETS",
    "best_configurations", "TourTrajectory", "tour_trajectory", "validate_trajectory",
    "held_karp", "milp_optimum",
    "MaxGenerations", "MaxRuntime", "NoImprovement", "TargetCost",
    "History", "PlanResult",
    "SubtaskOptError", "ParameterError", "InputDataError", "UnreachableError", "NoPathError",
]
