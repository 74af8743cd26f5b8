"""One robot, one problem, one solve for every arm: planar 2R arms and any serial chain.

>>> import subtask_opt as so
>>> robot = so.load_robot("ur5")                              # a name or a URDF path
>>> targets = so.load_targets("holes.csv", standoff=0.01)     # doctest: +SKIP
>>> problem = so.ArmProblem(targets, robot, home=[0, -1.57, 1.57, -1.57, -1.57, 0])
>>> result = so.solve(problem, seed=0)                        # doctest: +SKIP
>>> traj = so.trajectory(result); print(so.validate(traj))    # doctest: +SKIP

:func:`load_robot` detects the robot's family from its model: a 2-joint planar chain is a
planar arm (closed-form 2R IK; the Cartesian time models ``paper``, ``trapezoid`` and
``line`` are available), anything else a serial arm (UR and spherical-wrist closed forms,
else numerical IK; the ``joint`` model). :class:`ArmProblem` compiles the targets, robot,
scene and home into a tour problem of :mod:`subtask_opt.tour`; :func:`solve` solves it and
returns the one :class:`~subtask_opt.tour.solve.Result` type, whose ``report`` says what
the tour means for the arm. An option that does not apply to the robot is refused
(:class:`~subtask_opt.base.errors.ParameterError`), never ignored.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.base.stop import StoppingCriterion
from subtask_opt.tour.constraints import TourConstraints
from subtask_opt.tour.problem import ClusteredProblem, MatrixProblem
from subtask_opt.tour.solve import Result, SolverParams


@dataclass(frozen=True, eq=False)
class Robot:
    """A robot arm loaded from a URDF: a planar 2R arm or any serial chain.

    Attributes:
        name: the robot's name.
        planar: whether it is a planar 2R arm (points ``x, y`` as targets, the Cartesian
            time models available) rather than a serial arm (3-D pose targets).
        model: the kinematic model (:class:`~subtask_opt.kinematics.planar.Arm` for a planar
            arm, :class:`~subtask_opt.kinematics.serial.SerialArm` otherwise).
    """

    name: str
    planar: bool
    model: Any = field(repr=False)
    _loaded: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

    @property
    def nq(self) -> int:
        """Number of joints."""
        return 2 if self.planar else int(self.model.nq)

    def with_limits(self, *, velocity: Any = None, acceleration: Any = None,
                    jerk: Any = None, speed_scale: float = 1.0,
                    accel_scale: float = 1.0) -> Robot:
        """This robot with other joint limits: values (a scalar or one per joint) replace
        the model's, then ``speed_scale``/``accel_scale`` in (0, 1] scale the speed and the
        acceleration (and jerk) limits as fractions of them."""
        from subtask_opt.base.errors import require_in_range

        require_in_range("Robot.with_limits", "speed_scale", speed_scale, 1e-6, 1.0)
        require_in_range("Robot.with_limits", "accel_scale", accel_scale, 1e-6, 1.0)
        if self.planar:
            arm = self.model
            if velocity is not None or acceleration is not None or jerk is not None:
                arm = arm.with_joint_limits(velocity=velocity, acceleration=acceleration,
                                            jerk=jerk)
            if speed_scale != 1.0 or accel_scale != 1.0:
                lim = arm.joint_limits
                arm = arm.with_joint_limits(
                    velocity=np.asarray(lim.velocity) * speed_scale,
                    acceleration=np.asarray(lim.acceleration) * accel_scale,
                    jerk=None if lim.jerk is None else np.asarray(lim.jerk) * accel_scale)
            return replace(self, model=arm)
        arm = self.model
        lim = arm.limits
        n = arm.nq

        def per_joint(value: Any, old: Any, scale: float, what: str) -> Any:
            if value is None:
                return None if old is None else np.asarray(old, dtype=float) * scale
            arr = np.asarray(value, dtype=float).ravel()
            if arr.size not in (1, n) or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
                raise ParameterError(f"{what} must be one value > 0 or {n} of them, got "
                                     f"{arr.tolist()}")
            return np.broadcast_to(arr, (n,)).copy() * scale

        values = {
            "lower": np.asarray(lim.lower), "upper": np.asarray(lim.upper),
            "velocity": per_joint(velocity, lim.velocity, speed_scale, "velocity"),
            "acceleration": per_joint(acceleration, lim.acceleration, accel_scale,
                                      "acceleration"),
            "jerk": per_joint(jerk, lim.jerk, accel_scale, "jerk"),
        }
        from subtask_opt.kinematics.serial import load_serial_arm

        limits = {k: v.tolist() for k, v in values.items() if v is not None}
        loaded = {"name_or_path": arm.urdf_path, "tool_frame": arm.tool_frame,
                  "tool_offset": None, **self._loaded}
        return replace(self, model=load_serial_arm(loaded["name_or_path"],
                                                   tool_frame=loaded["tool_frame"],
                                                   tool_offset=loaded["tool_offset"],
                                                   limits=limits))


def load_robot(name_or_path: str | Path, *, tool_frame: str | None = None,
               tool_offset: Any = None, limits: Any = None) -> Robot:
    """Load a robot by name (``planar_2r``, ``asr_twodof``, ``ur3``, ``ur5``, ``ur10``,
    ``panda``, ``vs060_drill``) or from a URDF path (a 2-joint chain is a planar arm).

    Args:
        tool_frame: (serial arms) the frame that reaches the targets.
        tool_offset: (serial arms) a fixed transform from ``tool_frame`` to the tool, a
            4x4 matrix or ``(xyz, rpy)`` (metres, radians).
        limits: (serial arms) a named limit set of the robot, or a mapping of per-joint
            arrays (see :func:`~subtask_opt.kinematics.serial.load_serial_arm`).
    """
    from subtask_opt.kinematics.planar import ROBOT_NAMES, load_planar_arm
    from subtask_opt.kinematics.serial import SERIAL_ROBOT_NAMES, load_serial_arm

    text = str(name_or_path)
    planar = text in ROBOT_NAMES or (text not in SERIAL_ROBOT_NAMES
                                     and text.lower().endswith(".urdf")
                                     and movable_joints(text) == 2)
    if planar:
        for option, value in (("tool_frame", tool_frame), ("tool_offset", tool_offset),
                              ("limits", limits)):
            if value is not None:
                raise ParameterError(f"load_robot: {option} applies to serial arms; "
                                     f"{text} is a planar arm")
        arm = load_planar_arm(name_or_path)
        return Robot(name=arm.name, planar=True, model=arm)
    if text not in SERIAL_ROBOT_NAMES and not text.lower().endswith(".urdf"):
        raise ParameterError(f"unknown robot {text!r}: use one of "
                             f"{', '.join(ROBOT_NAMES + SERIAL_ROBOT_NAMES)} or a .urdf path")
    serial = load_serial_arm(name_or_path, tool_frame=tool_frame, tool_offset=tool_offset,
                             limits=limits)
    return Robot(name=serial.name, planar=False, model=serial,
                 _loaded={"name_or_path": name_or_path, "tool_frame": tool_frame,
                          "tool_offset": tool_offset})


def movable_joints(urdf: str | Path) -> int:
    """Number of revolute/prismatic/continuous joints of a URDF (-1 if unreadable)."""
    import xml.etree.ElementTree as ET

    from subtask_opt.base.files import check_input_file

    try:
        check_input_file(urdf, "URDF file")  # never parse a FIFO or a device: -1, reported later
        root = ET.parse(str(urdf)).getroot()
    except (OSError, ET.ParseError, InputDataError):
        return -1
    return sum(j.get("type") in ("revolute", "prismatic", "continuous")
               for j in root.iter("joint"))


def load_targets(path: str | Path, *, standoff: float = 0.0, axis_step: float = 45.0) -> Any:
    """Read targets from a CSV or JSON file: planar points (header ``x,y[,theta]``) give a
    planar :class:`~subtask_opt.arm.targets.Targets`, 3-D rows (``x,y,z,dx,dy,dz`` tool
    axes or ``x,y,z,qx,qy,qz,qw`` poses) 3-D ones.

    Args:
        standoff: (3-D targets) metres along the tool axis the tool stops short.
        axis_step: (3-D tool-axis targets) sampling step in degrees of the free rotation
            about the axis.
    """
    from subtask_opt.arm.poses import load_targets as load_poses
    from subtask_opt.arm.tasks import load_subtasks

    if _planar_file(Path(path)):
        for option, value, default in (("standoff", standoff, 0.0),
                                       ("axis_step", axis_step, 45.0)):
            if value != default:
                raise ParameterError(f"load_targets: {option} applies to 3-D targets; "
                                     f"{path} holds planar points")
        return load_subtasks(path)
    return load_poses(path, axis_step=axis_step, standoff=standoff)


def _planar_file(path: Path) -> bool:
    """Whether a target file holds planar points (x, y[, theta]) rather than 3-D targets."""
    import json

    from subtask_opt.base.files import read_text

    try:
        text = read_text(path, "target file", max_bytes=64 << 20)
    except OSError as exc:
        raise InputDataError(f"cannot read {path}: {exc}") from None
    if path.suffix.lower() == ".json":
        try:
            doc = json.loads(text)
        except (ValueError, RecursionError):
            return True  # the planar reader reports the error with its line
        rows = doc.get("subtasks", doc.get("targets")) if isinstance(doc, dict) else doc
        first = rows[0] if isinstance(rows, list) and rows else None
        if isinstance(first, dict):
            return "z" not in first
        return not (isinstance(first, list) and len(first) >= 6)
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            cells = [c.strip().lower() for c in line.split(",")]
            return "z" not in cells and len(cells) <= 3
    return True


@dataclass(frozen=True)
class Joints:
    """A home given as joint values (radians): a configuration of any arm.

    ``ArmProblem(home=Joints([q1, q2]))`` starts a planar arm's tour in that
    configuration (its tip point and elbow); a serial arm's home is a configuration
    anyway (``home=[q1, ..., qn]`` means the same).
    """

    values: tuple[float, ...]

    def __post_init__(self) -> None:
        try:
            q = np.asarray(self.values, dtype=float).ravel()
        except (TypeError, ValueError):
            q = np.full(1, np.nan)
        if q.size == 0 or not np.all(np.isfinite(q)):
            raise ParameterError(f"Joints needs finite joint values (radians), got "
                                 f"{self.values!r}")
        object.__setattr__(self, "values", tuple(float(v) for v in q))


PLANAR_ONLY = ("time_model", "k", "elbow", "configurations", "line_fallback",
               "check_all_legs")
SERIAL_ONLY = ("scene", "clearance", "ik_seed", "detours", "detour")


@dataclass(frozen=True, eq=False)
class ArmProblem:
    """Targets, the robot that visits them, its cell and home: what :func:`solve` takes.

    Attributes:
        targets: planar points (:func:`load_targets` of an ``x,y`` file, or
            :func:`~subtask_opt.arm.tasks.builtin_case`) for a planar arm; pose targets for
            a serial arm.
        robot: the robot (:func:`load_robot`).
        home: where the tour starts and (closed) ends. Any arm: a configuration,
            :class:`Joints` (radians); a serial arm's home is also a plain sequence of
            joint values (default the robot file's ``home_deg``); a planar arm's a plain
            *point* ``(x, y)`` (default: none, the tour starts at a subtask).
        scene: (serial arms) a scene file or :class:`~subtask_opt.cell.scene.Scene`.
        time_model: ``joint`` (every robot); ``line``, ``trapezoid``, ``paper``
            (planar arms: Cartesian models).
        k, elbow, configurations, line_fallback, check_all_legs: planar options (see
            :class:`~subtask_opt.arm.planar_problem.PlanarProblem`).
        clearance: (serial arms) leg sweep resolution in metres.
        detours: (serial arms) plan legs in collision around the obstacles (OMPL,
            :mod:`subtask_opt.cell.detour`); False forbids them.
        detour: (serial arms) the planner's budgets, a
            :class:`~subtask_opt.cell.detour.DetourParams` (default: its defaults).
        first: the target a planar closed tour starts at (default the first).

    Built on construction: IK, collision checks and leg times (``compiled``: the
    :class:`~subtask_opt.arm.planar_problem.PlanarProblem` or
    :class:`~subtask_opt.arm.serial_problem.SerialProblem` behind it).
    """

    targets: Any
    robot: Robot
    home: Any = None
    scene: Any = None
    time_model: str = "joint"
    k: float = 0.1
    elbow: int = 0
    configurations: str | None = None
    line_fallback: str = "joint"
    check_all_legs: bool = False
    clearance: float = 0.01
    ik_seed: int = 0
    detours: bool = True
    detour: Any = None
    first: int | None = None
    compiled: Any = field(init=False, repr=False)
    # a planar home as the compiled problem takes it: the tip point and, for a home
    # configuration, its elbow branch (None: a point, either elbow)
    _planar_home: tuple[tuple[float, float], int | None] | None = field(
        init=False, repr=False, default=None)

    def __post_init__(self) -> None:
        if not isinstance(self.robot, Robot):
            raise ParameterError(f"ArmProblem.robot must be a Robot (load_robot), got "
                                 f"{type(self.robot).__name__}")
        defaults = {f: type(self).__dataclass_fields__[f].default
                    for f in PLANAR_ONLY + SERIAL_ONLY}
        wrong = SERIAL_ONLY if self.robot.planar else PLANAR_ONLY
        for name in wrong:
            value = getattr(self, name)
            if name == "time_model" and value == "joint":
                continue
            if value != defaults[name]:
                kind = "serial" if self.robot.planar else "planar"
                raise ParameterError(f"ArmProblem.{name}={value!r} applies to {kind} arms "
                                     f"only; {self.robot.name} is "
                                     f"{'planar' if self.robot.planar else 'a serial arm'}")
        object.__setattr__(self, "compiled", self._planar() if self.robot.planar
                           else self._serial())

    def _planar(self) -> Any:
        from subtask_opt.arm.planar_problem import PlanarProblem

        _check_targets(self.targets, True, self.robot, "planar points (load_targets "
                       "of an x,y file)")
        if isinstance(self.home, Joints):
            object.__setattr__(self, "_planar_home", _planar_home_configuration(
                self.robot.model, np.array(self.home.values)))
        elif self.home is not None:
            try:
                home = np.asarray(self.home, dtype=float)
            except (TypeError, ValueError):
                home = np.zeros(0)
            if home.shape != (2,) or not np.all(np.isfinite(home)):
                raise ParameterError(f"a planar arm's home is a point (x, y) in metres or "
                                     f"a configuration Joints([q1, q2]), got {self.home!r}")
            object.__setattr__(self, "_planar_home", ((float(home[0]), float(home[1])), None))
        return PlanarProblem(self.targets, self.robot.model, time_model=self.time_model,
                             first=self.first, k=self.k, elbow=self.elbow,
                             configurations=self.configurations,
                             line_fallback=self.line_fallback,
                             check_all_legs=self.check_all_legs)

    def _serial(self) -> Any:
        from subtask_opt.arm.serial_problem import SerialProblem, default_home
        from subtask_opt.cell.scene import Scene

        _check_targets(self.targets, False, self.robot, "3-D (load_targets of an "
                       "x,y,z,... file)")
        if self.first is not None:
            raise ParameterError("ArmProblem.first applies to planar arms; a serial arm's "
                                 "tour starts at its home (TourConstraints(start=I) for the "
                                 "first target)")
        home = self.home.values if isinstance(self.home, Joints) else self.home
        if home is None:
            home = default_home(self.robot.model)
            if home is None:
                raise ParameterError(f"{self.robot.name} has no default home: give "
                                     f"home=[q1, ..., q{self.robot.nq}] in radians")
        scene = self.scene
        if isinstance(scene, (str, Path)):
            scene = Scene.load(scene)
        if scene is not None and not isinstance(scene, Scene):
            raise ParameterError(f"ArmProblem.scene must be a scene file or a Scene, got "
                                 f"{type(scene).__name__}")
        if scene is not None and scene.tool is not None:
            loaded = self.robot._loaded
            if loaded.get("tool_offset") is not None or loaded.get("tool_frame") is not None:
                raise ParameterError("the scene's tool defines the TCP: load the robot "
                                     "without tool_frame/tool_offset (--tool-frame), or "
                                     "drop the scene's 'tool'")
        return SerialProblem(self.targets, self.robot.model, home, scene=scene,
                             clearance=self.clearance, ik_seed=self.ik_seed,
                             detours=self.detours, detour=self.detour)

    @property
    def size(self) -> int:
        """Number of targets."""
        return int(self.compiled.size)


def _planar_home_configuration(arm: Any, q: np.ndarray) -> tuple[tuple[float, float], int]:
    """A planar home configuration as (tip point, elbow branch), checked to be the arm's
    IK solution of that point on that branch (inside the joint limits)."""
    lim = arm.joint_limits
    if q.shape != (2,):
        raise ParameterError(f"a planar arm's home configuration has 2 joint values, got "
                             f"{q.size}")
    if np.any(q < lim.lower) or np.any(q > lim.upper):
        raise InputDataError(f"home configuration {np.round(q, 6).tolist()} rad is outside "
                             f"the joint limits [{lim.lower.tolist()}, {lim.upper.tolist()}]")
    point = np.asarray(arm.fk(q), dtype=float)[:2]
    branches = arm.ik(point)
    miss = np.abs(np.angle(np.exp(1j * (branches - q)))).max(axis=1)
    miss[~np.isfinite(miss)] = np.inf
    branch = int(np.argmin(miss))
    if miss[branch] > 1e-6:
        raise InputDataError(f"home configuration {np.round(q, 6).tolist()} rad is on "
                             "neither elbow branch of the arm's IK (a singular or wrapped "
                             "configuration)")
    return (float(point[0]), float(point[1])), branch


def _check_targets(targets: Any, planar: bool, robot: Robot, what: str) -> None:
    from subtask_opt.arm.targets import Targets, describe

    if not isinstance(targets, Targets) or targets.planar != planar:
        family = "a planar arm" if robot.planar else "a serial arm"
        raise ParameterError(f"{robot.name} is {family}: its targets are {what}, got "
                             f"{describe(targets)}")


def solve(problem: ArmProblem | MatrixProblem | ClusteredProblem | Any, *, seed: int = 0,
          stop: StoppingCriterion | list[StoppingCriterion] | None = None,
          params: SolverParams | None = None, progress: bool = False,
          certify: bool = False, certify_time_limit: float = 60.0,
          constraints: TourConstraints | None = None) -> Result:
    """Find a minimum-time tour of an arm problem (or of a tour problem).

    Args:
        problem: an :class:`ArmProblem`, or a robot-free
            :class:`~subtask_opt.tour.problem.MatrixProblem` /
            :class:`~subtask_opt.tour.problem.ClusteredProblem`.
        seed: in [0, 2**63); the same seed gives the same result.
        stop: stopping criteria (any of them stops the search); default per problem size.
        params: search parameters (:class:`~subtask_opt.tour.solve.SolverParams`).
        progress: a progress bar on a terminal.
        certify: prove the answer optimal, or say why not (``Result.certified``).
        constraints: the tour's shape and precedence
            (:class:`~subtask_opt.tour.constraints.TourConstraints`): a closed tour
            (default) or an open path, a first (``start``) and last (``end``) target,
            precedence pairs. A serial arm's tour always starts at its home; a planar
            arm's home point is ``ArmProblem(home=(x, y))``.

    Returns:
        The :class:`~subtask_opt.tour.solve.Result`; for an arm problem its
        ``configurations`` hold every target's joint vector (input order), ``cpu`` the
        CPU seconds per phase, and ``report`` what the tour means for the arm.
    """
    from subtask_opt.arm import planar_problem
    from subtask_opt.arm.serial_problem import solve_serial_problem

    if not isinstance(problem, ArmProblem):
        return planar_problem.solve(problem, seed=seed, stop=stop, params=params,
                                    progress=progress, certify=certify,
                                    certify_time_limit=certify_time_limit,
                                    constraints=constraints)
    if not problem.robot.planar:
        return solve_serial_problem(problem.compiled, seed=seed, stop=stop, params=params,
                                    progress=progress, certify=certify,
                                    certify_time_limit=certify_time_limit,
                                    constraints=constraints)
    branch = None
    if problem._planar_home is not None:
        if constraints is not None and constraints.home is not None:
            raise ParameterError("give the home once: ArmProblem(home=...) or "
                                 "TourConstraints(home=...), not both")
        point, branch = problem._planar_home
        constraints = replace(constraints or TourConstraints(), home=point)
    return planar_problem.solve(problem.compiled, seed=seed, stop=stop, params=params,
                                progress=progress, certify=certify,
                                certify_time_limit=certify_time_limit, constraints=constraints,
                                home_branch=branch)


def trajectory(result: Result) -> Any:
    """The executable joint trajectory of an arm problem's answer
    (:func:`~subtask_opt.arm.trajectory.build_trajectory`): ruckig joint moves, and a
    planar arm's straight lines time-parameterised as its time model timed them."""
    from subtask_opt.arm.trajectory import build_trajectory

    return build_trajectory(result)


def validate(trajectory: Any, *, dt: float | None = None) -> Any:
    """Check a :func:`trajectory` densely (:func:`~subtask_opt.arm.trajectory.validate`):
    joint limits (jerk included), rest at the stops, FK at every target, the duration
    against the planned time, and collisions where the problem has a checker."""
    from subtask_opt.arm.trajectory import validate as check

    return check(trajectory, dt=dt)


__all__ = ["ArmProblem", "Joints", "Robot", "load_robot", "load_targets", "movable_joints", "solve",
           "trajectory", "validate"]
