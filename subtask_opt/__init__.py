"""subtask_opt: minimum-time subtask sequencing for a robot arm, and mobile-robot planners.

The sequencing API::

    from subtask_opt import load_arm, builtin_case, SequencingProblem, solve
    arm = load_arm("planar_2r")
    problem = SequencingProblem(builtin_case("random30", arm, seed=0), arm)
    result = solve(problem, seed=1)
    print(result.summary())

Planners live in :mod:`subtask_opt.planners`; figures in :mod:`subtask_opt.plotting`.
"""

from subtask_opt import _kernel_cache  # noqa: F401  (first: selects numba's cache folder)
from subtask_opt.arm.configurations import best_configurations
from subtask_opt.arm.constraints import TourConstraints
from subtask_opt.arm.exact import exact_constrained, held_karp, milp_optimum
from subtask_opt.arm.model import ROBOT_NAMES, Arm, CartesianLimits, JointLimits, load_arm
from subtask_opt.arm.report import TourReport
from subtask_opt.arm.sequencing import (
    DEFAULT_TIME_MODEL,
    PRESETS,
    MatrixProblem,
    Result,
    SequencingProblem,
    SolverParams,
    solve,
)
from subtask_opt.arm.tasks import CASE_NAMES, SubtaskSet, builtin_case, load_subtasks, save_subtasks
from subtask_opt.arm.timing.models import TIME_MODELS, LegCheck, TimingResult, travel_times
from subtask_opt.arm.trajectory import TourTrajectory, tour_trajectory, validate_trajectory
from subtask_opt.base.errors import (
    InputDataError,
    NoPathError,
    ParameterError,
    SubtaskOptError,
    UnreachableError,
)
from subtask_opt.base.results import History, PlanResult
from subtask_opt.base.stop import MaxGenerations, MaxRuntime, NoImprovement, TargetCost

__version__ = "0.1.0"

__all__ = [
    "Arm", "CartesianLimits", "JointLimits", "load_arm", "ROBOT_NAMES",
    "SubtaskSet", "builtin_case", "load_subtasks", "save_subtasks", "CASE_NAMES",
    "TIME_MODELS", "LegCheck", "TimingResult", "travel_times",
    "SequencingProblem", "MatrixProblem", "SolverParams", "Result", "TourReport", "solve",
    "PRESETS", "DEFAULT_TIME_MODEL",
    "best_configurations", "TourTrajectory", "tour_trajectory", "validate_trajectory",
    "held_karp", "milp_optimum", "TourConstraints", "exact_constrained",
    "MaxGenerations", "MaxRuntime", "NoImprovement", "TargetCost",
    "History", "PlanResult",
    "SubtaskOptError", "ParameterError", "InputDataError", "UnreachableError", "NoPathError",
]
