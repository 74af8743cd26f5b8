"""subtask_opt: minimum-time subtask sequencing for a robot arm, and mobile-robot planners.

One API for every arm, a planar 2R arm or any serial chain (UR, Panda, VS060, a URDF)::

    import subtask_opt as so
    robot = so.load_robot("ur5")                         # or "planar_2r", or a URDF path
    targets = so.load_targets("holes.csv", standoff=0.01)
    problem = so.ArmProblem(targets, robot, scene="cell.json",
                            home=[0, -1.57, 1.57, -1.57, -1.57, 0])
    result = so.solve(problem, seed=0, constraints=so.TourConstraints(tour="open"))
    print(result.summary()); traj = so.trajectory(result); print(so.validate(traj))

Robot-free tours (a cost matrix, a clustered cost tensor, TSPLIB) live in
:mod:`subtask_opt.tour` and take the same :func:`solve`; planners live in
:mod:`subtask_opt.planners`; figures in :mod:`subtask_opt.plotting`.
"""

from importlib import import_module
from typing import TYPE_CHECKING, Any

from subtask_opt import _kernel_cache  # noqa: F401  (first: selects numba's cache folder)

if TYPE_CHECKING:
    from subtask_opt.arm.planar_problem import DEFAULT_TIME_MODEL
    from subtask_opt.arm.problem import (
        ArmProblem,
        Joints,
        Robot,
        load_robot,
        load_targets,
        solve,
        trajectory,
        validate,
    )
    from subtask_opt.arm.report import TourReport
    from subtask_opt.arm.targets import Targets
    from subtask_opt.arm.tasks import CASE_NAMES, builtin_case, save_subtasks
    from subtask_opt.arm.timing.models import TIME_MODELS
    from subtask_opt.base.errors import (
        InputDataError,
        NoPathError,
        ParameterError,
        SubtaskOptError,
        UnreachableError,
    )
    from subtask_opt.base.results import History, PlanResult
    from subtask_opt.base.stop import MaxGenerations, MaxRuntime, NoImprovement, TargetCost
    from subtask_opt.tour.constraints import TourConstraints
    from subtask_opt.tour.exact import exact_constrained, held_karp, milp_optimum
    from subtask_opt.tour.problem import ClusteredProblem, MatrixProblem
    from subtask_opt.tour.solve import PRESETS, Result, SolverParams

# The public names are loaded on first use (PEP 562), so that a command starts, and can say
# that it is compiling, before Pinocchio, the solver and the time models are imported.
_SOURCES: dict[str, tuple[str, ...]] = {
    "subtask_opt.arm.planar_problem": ("DEFAULT_TIME_MODEL",),
    "subtask_opt.arm.problem": (
        "ArmProblem", "Joints", "Robot", "load_robot", "load_targets", "solve",
        "trajectory", "validate",
    ),
    "subtask_opt.arm.report": ("TourReport",),
    "subtask_opt.arm.targets": ("Targets",),
    "subtask_opt.arm.tasks": ("CASE_NAMES", "builtin_case", "save_subtasks",),
    "subtask_opt.arm.timing.models": ("TIME_MODELS",),
    "subtask_opt.base.errors": (
        "InputDataError", "NoPathError", "ParameterError", "SubtaskOptError",
        "UnreachableError",
    ),
    "subtask_opt.base.results": ("History", "PlanResult",),
    "subtask_opt.base.stop": ("MaxGenerations", "MaxRuntime", "NoImprovement", "TargetCost",),
    "subtask_opt.tour.constraints": ("TourConstraints",),
    "subtask_opt.tour.exact": ("exact_constrained", "held_karp", "milp_optimum",),
    "subtask_opt.tour.problem": ("ClusteredProblem", "MatrixProblem",),
    "subtask_opt.tour.solve": ("PRESETS", "Result", "SolverParams",),
}
_MODULE_OF = {name: module for module, names in _SOURCES.items() for name in names}


def __getattr__(name: str) -> Any:
    module = _MODULE_OF.get(name)
    if module is None:
        raise AttributeError(f"module 'subtask_opt' has no attribute {name!r}")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_MODULE_OF))


__version__ = "0.1.0"

__all__ = [
    "load_robot", "Robot", "load_targets", "ArmProblem", "Joints", "solve", "Result", "trajectory",
    "validate", "TourConstraints", "SolverParams", "PRESETS", "DEFAULT_TIME_MODEL",
    "TIME_MODELS", "TourReport",
    "Targets", "builtin_case", "save_subtasks", "CASE_NAMES",
    "MatrixProblem", "ClusteredProblem", "held_karp", "milp_optimum", "exact_constrained",
    "MaxGenerations", "MaxRuntime", "NoImprovement", "TargetCost",
    "History", "PlanResult",
    "SubtaskOptError", "ParameterError", "InputDataError", "UnreachableError", "NoPathError",
]
