"""Every inverse-kinematics solution of a serial arm for a tool pose.

Two methods, one result: all distinct joint vectors within the joint limits
whose tool frame reaches the pose (Pinocchio FK, to ``accept_tol``).

* **Closed form** for the Universal Robots family (``ur3``, ``ur5``, ``ur10`` of
  example-robot-data): the classic 8-branch solution (shoulder left/right x wrist
  flip x elbow up/down) written from the standard UR Denavit-Hartenberg table

  ====  ==========  =====  =====  ======
  i     alpha_i     a_i    d_i    theta_i
  ====  ==========  =====  =====  ======
  1     pi/2        0      d1     q1
  2     0           a2     0      q2
  3     0           a3     0      q3
  4     pi/2        0      d4     q4
  5     -pi/2       0      d5     q5
  6     0           0      d6     q6
  ====  ==========  =====  =====  ======

  with ``A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``. a2, a3, d1, d4, d5 are
  read from the URDF's joint placements; the base frame ``W`` (world -> DH frame
  0) and the flange-to-tool transform ``E`` are measured from Pinocchio at q = 0,
  so ``tool(q) = W A_1...A_6 E``. The table is then checked against Pinocchio FK
  at random configurations; if that check fails (a different arm or URDF
  convention) the closed form is not used.
* **Closed form for 6R arms with a spherical wrist** (``vs060_drill``; any arm
  whose axes 4, 5, 6 meet in one point and whose axes 2 and 3 are parallel), see
  :class:`SphericalWristKinematics`: the geometry is read from the model at q = 0
  (joint axes and points measured with Pinocchio, so shoulder, lateral and elbow
  offsets and a tilted base are handled), the wrist centre gives q1 (two shoulder
  branches), q3 (two elbow branches) and q2, and the wrist rotation gives q4, q5,
  q6 by Paden-Kahan subproblems (two wrist branches): up to 8 candidates. Accepted
  only when its FK matches Pinocchio's and it recovers random configurations
  (:func:`spherical_wrist_kinematics`); otherwise DLS is used. All candidate poses
  of :meth:`IKSolver.solve_targets` are solved in one numpy batch (245 RoboTSP
  holes x 8 axis samples in about 0.1 s CPU, against about 29 s by DLS).
* **Damped least squares** (any arm): Levenberg-Marquardt steps
  ``dq = J^T (J J^T + damping^2 I)^-1 e`` with the world-frame error
  ``e = (p_target - p, log3(R_target R^T))`` and the world-aligned Jacobian,
  run for all ``starts`` random configurations at once (numpy batches over a
  copy of the chain read from Pinocchio). Starts are drawn uniformly inside the
  joint limits (revolute joints within [-pi, pi]) from
  ``np.random.default_rng(seed)``; a start stops when its error is below 1e-11,
  or when the error has not halved over 15 iterations. For a 6-DOF arm this
  finds the isolated solutions with high probability but not with certainty
  (on the UR5 it matches the closed form's 8 in the tests); for a 7-DOF arm the
  solutions form a continuum and the result is a sample of it.

Candidates are wrapped into the limits and de-duplicated: two solutions are the
same when every revolute joint differs by less than ``dedup_tol`` rad modulo
2 pi (prismatic: in value). Each survivor is checked by Pinocchio FK (polished
by up to 5 Gauss-Newton steps on Pinocchio's SE(3) log error when it misses by
more than ``accept_tol``, dropped if it still does). Finally, each revolute
joint takes every value ``q + 2 pi k`` inside its limits, so a joint whose range
exceeds 2 pi contributes its +-2 pi alternatives (the UR's +-2 pi joints double
the count per joint).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from subtask_opt.base.errors import ParameterError, require_in_range, require_int
from subtask_opt.kinematics.serial import SerialArm, as_pose_array

METHODS: tuple[str, ...] = ("auto", "closed_form", "dls")
TWO_PI = 2.0 * math.pi
_UR_ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)
_STALL = 15  # DLS gives up when the error has not halved over this many iterations

Seed = int | Sequence[int] | None
"""A seed for ``np.random.default_rng`` (None: fresh entropy)."""


def _check_seed(seed: Seed) -> None:
    """ParameterError unless seed is None, an int >= 0 or a sequence of them."""
    if seed is None:
        return
    if isinstance(seed, Sequence) and not isinstance(seed, str):
        for value in seed:
            require_int("IKSolver", "seed", value, 0)
        return
    require_int("IKSolver", "seed", seed, 0)  # type: ignore[arg-type]


@dataclass(frozen=True)
class IKParams:
    """Settings of :class:`IKSolver`.

    Attributes:
        method: ``"auto"`` (closed form when the arm has one, else DLS),
            ``"closed_form"`` (error if the arm has none) or ``"dls"``.
        starts: DLS random starts per pose.
        max_iter: DLS iterations per start.
        damping: Levenberg-Marquardt damping lambda (the step solves
            (J J^T + lambda^2 I) v = -e).
        max_step: largest joint step per iteration (rad, infinity norm).
        accept_tol: a solution is kept when its FK misses the pose by at most this
            (m for position, rad for rotation).
        dedup_tol: joint-space distance (rad, max norm, modulo 2 pi) below which two
            solutions are the same.
        wrap_alternatives: add the q + 2 pi k alternatives of revolute joints.
    """

    method: str = "auto"
    starts: int = 64
    max_iter: int = 100
    damping: float = 1e-3
    max_step: float = 0.5
    accept_tol: float = 1e-9
    dedup_tol: float = 1e-4
    wrap_alternatives: bool = True

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ParameterError(f"IKParams.method must be one of {', '.join(METHODS)}, "
                                 f"got {self.method!r}")
        require_int("IKParams", "starts", self.starts, 1, 100_000)
        require_int("IKParams", "max_iter", self.max_iter, 1, 100_000)
        require_in_range("IKParams", "damping", self.damping, 0.0, 1.0)
        require_in_range("IKParams", "max_step", self.max_step, 1e-6, 10.0)
        require_in_range("IKParams", "accept_tol", self.accept_tol, 1e-15, 1e-3)
        require_in_range("IKParams", "dedup_tol", self.dedup_tol, 1e-12, 0.1)
        if not isinstance(self.wrap_alternatives, bool):
            raise ParameterError(f"IKParams.wrap_alternatives must be a bool, "
                                 f"got {self.wrap_alternatives!r}")


@dataclass(frozen=True, eq=False)
class TargetSolutions:
    """IK solutions of a set of pose targets.

    Attributes:
        configurations: per target, a read-only (m_i, nq) array of joint solutions
            (m_i may be 0: unreachable within the limits).
        pose_index: per target, (m_i,) index of the candidate pose (in
            ``Targets.poses[i]``) each solution reaches.
        method: the method used (``"closed_form"`` or ``"dls"``).
    """

    configurations: tuple[np.ndarray, ...]
    pose_index: tuple[np.ndarray, ...]
    method: str

    def __post_init__(self) -> None:
        if len(self.configurations) != len(self.pose_index):
            raise ParameterError("TargetSolutions.configurations and pose_index must have the "
                                 "same length")
        for i, (q, k) in enumerate(zip(self.configurations, self.pose_index, strict=True)):
            if q.ndim != 2 or k.shape != (q.shape[0],):
                raise ParameterError(f"TargetSolutions entry {i}: shapes {q.shape} and "
                                     f"{k.shape} do not match")
            q.setflags(write=False)
            k.setflags(write=False)

    @property
    def counts(self) -> np.ndarray:
        """(n,) number of solutions per target."""
        return np.array([q.shape[0] for q in self.configurations], dtype=np.int64)

    def unreachable(self) -> list[int]:
        """Indices of the targets with no solution."""
        return [i for i, q in enumerate(self.configurations) if q.shape[0] == 0]


# ---------------------------------------------------------------- UR closed form

def _dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    ct, st = math.cos(theta), math.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct],
                     [st, ct * ca, -ct * sa, a * st],
                     [0.0, sa, ca, d],
                     [0.0, 0.0, 0.0, 1.0]])


def _inv(t: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = t[:3, :3].T
    out[:3, 3] = -t[:3, :3].T @ t[:3, 3]
    return out


def _dh_batch(theta: np.ndarray, d: float, a: float, alpha: float) -> np.ndarray:
    """:func:`_dh` of every angle in ``theta`` (P,): (P, 4, 4)."""
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    out = np.zeros((theta.shape[0], 4, 4))
    out[:, 0, 0], out[:, 0, 1], out[:, 0, 2], out[:, 0, 3] = ct, -st * ca, st * sa, a * ct
    out[:, 1, 0], out[:, 1, 1], out[:, 1, 2], out[:, 1, 3] = st, ct * ca, -ct * sa, a * st
    out[:, 2, 1], out[:, 2, 2], out[:, 2, 3] = sa, ca, d
    out[:, 3, 3] = 1.0
    return out


def _inv_batch(t: np.ndarray) -> np.ndarray:
    """:func:`_inv` of every rigid transform in ``t`` (P, 4, 4)."""
    out = np.zeros_like(t)
    rt = np.transpose(t[:, :3, :3], (0, 2, 1))
    out[:, :3, :3] = rt
    out[:, :3, 3] = -(rt @ t[:, :3, 3, None])[:, :, 0]
    out[:, 3, 3] = 1.0
    return out


@dataclass(frozen=True, eq=False)
class URKinematics:
    """The UR Denavit-Hartenberg parameters of an arm and its base/tool transforms.

    Attributes:
        d1, a2, a3, d4, d5, d6: DH lengths (m), see the module doc.
        base: 4x4 world -> DH frame 0.
        flange_to_tool: 4x4 DH frame 6 -> tool frame.
    """

    d1: float
    a2: float
    a3: float
    d4: float
    d5: float
    d6: float
    base: np.ndarray
    flange_to_tool: np.ndarray

    def fk(self, q: Any) -> np.ndarray:
        """Tool pose (4x4) by the DH table (independent of Pinocchio)."""
        d = (self.d1, 0.0, 0.0, self.d4, self.d5, self.d6)
        a = (0.0, self.a2, self.a3, 0.0, 0.0, 0.0)
        t = self.base.copy()
        for i in range(6):
            t = t @ _dh(float(q[i]), d[i], a[i], _UR_ALPHA[i])
        return t @ self.flange_to_tool

    def solve_batch(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`solve` for poses (P, 4, 4) at once: (P, 8, 6) angles in (-pi, pi] and a
        (P, 8) mask of the candidates that exist (the same branches, in the same order).

        Candidate ``b = 4 s + 2 w + e`` (shoulder s, wrist w, elbow e) as :meth:`solve`
        lists them; a branch whose step has no real root is masked out.
        """
        n_pose = poses.shape[0]
        d1, a2, a3, d4, d5, d6 = self.d1, self.a2, self.a3, self.d4, self.d5, self.d6
        t06 = _inv(self.base) @ poses @ _inv(self.flange_to_tool)
        p06 = t06[:, :3, 3]
        p05 = p06 - d6 * t06[:, :3, 2]
        radius = np.hypot(p05[:, 0], p05[:, 1])
        reach = (radius >= abs(d4)) & (radius > 0.0)
        safe = np.where(reach, radius, 1.0)
        psi = np.arctan2(p05[:, 1], p05[:, 0])
        phi = np.arcsin(np.clip(d4 / safe, -1.0, 1.0))
        sol = np.zeros((n_pose, 8, 6))
        valid = np.zeros((n_pose, 8), dtype=bool)
        for s, th1 in enumerate((psi + phi, psi + math.pi - phi)):
            z1 = np.stack([np.sin(th1), -np.cos(th1), np.zeros(n_pose)], axis=1)
            c5 = (np.einsum("pi,pi->p", p06, z1) - d4) / d6
            ok5 = reach & (np.abs(c5) <= 1.0 + 1e-12)
            c5 = np.clip(c5, -1.0, 1.0)
            a1_inv = _inv_batch(_dh_batch(th1, d1, 0.0, _UR_ALPHA[0]))
            for w, th5 in enumerate((np.arccos(c5), -np.arccos(c5))):
                s5 = np.sin(th5)
                v = np.einsum("pji,pj->pi", t06[:, :3, :3], z1)
                small = np.abs(s5) < 1e-12
                s5_safe = np.where(small, 1.0, s5)
                th6 = np.where(small, 0.0, np.arctan2(-v[:, 1] / s5_safe, v[:, 0] / s5_safe))
                a5_inv = _inv_batch(_dh_batch(th5, d5, 0.0, _UR_ALPHA[4]))
                a6_inv = _inv_batch(_dh_batch(th6, d6, 0.0, _UR_ALPHA[5]))
                t14 = a1_inv @ t06 @ a6_inv @ a5_inv
                px, py = t14[:, 0, 3], t14[:, 1, 3]
                c3 = (px * px + py * py - a2 * a2 - a3 * a3) / (2.0 * a2 * a3)
                ok3 = ok5 & (np.abs(c3) <= 1.0 + 1e-12)
                c3 = np.clip(c3, -1.0, 1.0)
                for e, th3 in enumerate((np.arccos(c3), -np.arccos(c3))):
                    s3 = np.sin(th3)
                    th2 = np.arctan2(py, px) - np.arctan2(a3 * s3, a2 + a3 * c3)
                    th4 = np.arctan2(t14[:, 1, 0], t14[:, 0, 0]) - th2 - th3
                    b = 4 * s + 2 * w + e
                    sol[:, b] = np.stack([th1, th2, th3, th4, th5, th6], axis=1)
                    valid[:, b] = ok3
        return (sol + math.pi) % TWO_PI - math.pi, valid

    def solve(self, pose: np.ndarray) -> np.ndarray:
        """All (<= 8) closed-form solutions for a 4x4 tool pose, angles in (-pi, pi]."""
        t06 = _inv(self.base) @ pose @ _inv(self.flange_to_tool)
        d1, a2, a3, d4, d5, d6 = self.d1, self.a2, self.a3, self.d4, self.d5, self.d6
        p06 = t06[:3, 3]
        p05 = p06 - d6 * t06[:3, 2]
        radius = math.hypot(p05[0], p05[1])
        out: list[list[float]] = []
        if radius < abs(d4) or radius == 0.0:
            return np.zeros((0, 6))
        psi = math.atan2(p05[1], p05[0])
        phi = math.asin(max(-1.0, min(1.0, d4 / radius)))
        for th1 in (psi + phi, psi + math.pi - phi):
            z1 = np.array([math.sin(th1), -math.cos(th1), 0.0])
            c5 = (float(p06 @ z1) - d4) / d6
            if abs(c5) > 1.0 + 1e-12:
                continue
            c5 = max(-1.0, min(1.0, c5))
            for th5 in (math.acos(c5), -math.acos(c5)):
                s5 = math.sin(th5)
                v = t06[:3, :3].T @ z1
                th6 = 0.0 if abs(s5) < 1e-12 else math.atan2(-v[1] / s5, v[0] / s5)
                a1_inv = _inv(_dh(th1, d1, 0.0, _UR_ALPHA[0]))
                a5_inv = _inv(_dh(th5, d5, 0.0, _UR_ALPHA[4]))
                a6_inv = _inv(_dh(th6, d6, 0.0, _UR_ALPHA[5]))
                t14 = a1_inv @ t06 @ a6_inv @ a5_inv
                px, py = t14[0, 3], t14[1, 3]
                c3 = (px * px + py * py - a2 * a2 - a3 * a3) / (2.0 * a2 * a3)
                if abs(c3) > 1.0 + 1e-12:
                    continue
                c3 = max(-1.0, min(1.0, c3))
                for th3 in (math.acos(c3), -math.acos(c3)):
                    s3 = math.sin(th3)
                    th2 = math.atan2(py, px) - math.atan2(a3 * s3, a2 + a3 * c3)
                    th4 = math.atan2(t14[1, 0], t14[0, 0]) - th2 - th3
                    out.append([th1, th2, th3, th4, th5, th6])
        if not out:
            return np.zeros((0, 6))
        sol = np.array(out)
        return (sol + math.pi) % TWO_PI - math.pi


def ur_kinematics(arm: SerialArm, *, checks: int = 20, tol: float = 1e-9) -> URKinematics | None:
    """The UR DH description of ``arm`` if it has the UR structure and FK agrees, else None.

    The structure read is ur_description's: joint placements (0, 0, d1),
    (0, y2, 0), (0, y3, -a2), (0, 0, -a3), (0, y5, 0), (0, 0, d5) with
    d4 = y2 + y3 + y5. The table is accepted only when its FK matches Pinocchio's
    to ``tol`` at ``checks`` random configurations (seed 0).
    """
    import pinocchio as pin

    model = arm.model
    if arm.nq != 6 or not arm.revolute.all() or model.njoints != 7:
        return None
    if any(model.parents[i] != i - 1 for i in range(1, 7)):
        return None
    tr = [np.array(model.jointPlacements[i].translation) for i in range(1, 7)]
    d1 = float(tr[0][2])
    a2 = -float(tr[2][2])
    a3 = -float(tr[3][2])
    d4 = float(tr[1][1] + tr[2][1] + tr[4][1])
    d5 = float(tr[5][2])
    if min(abs(a2), abs(a3), abs(d4)) < 1e-6:
        return None
    # d6 places the DH flange on the last axis; any non-zero value works since the
    # flange-to-tool transform absorbs it. Use the tool's distance when it has one.
    tool_pos = np.array(model.frames[arm.tool_frame_id].placement.translation)
    d6 = float(np.linalg.norm(tool_pos)) if np.linalg.norm(tool_pos) > 1e-3 else 0.1
    data = model.createData()
    q0 = np.zeros(6)
    pin.forwardKinematics(model, data, q0)
    joint1 = np.array(data.oMi[1].homogeneous)
    tool0 = np.array(pin.updateFramePlacement(model, data, arm.tool_frame_id).homogeneous)
    rng = np.random.default_rng(0)
    samples = rng.uniform(-math.pi, math.pi, size=(checks, 6))
    for yaw in (0.0, math.pi / 2, math.pi, -math.pi / 2):
        base = joint1 @ _dh(yaw, -d1, 0.0, 0.0)  # joint 1 frame, down d1, turned by yaw
        partial = URKinematics(d1, a2, a3, d4, d5, d6, base, np.eye(4))
        flange_to_tool = _inv(partial.fk(q0)) @ tool0
        kin = URKinematics(d1, a2, a3, d4, d5, d6, base, flange_to_tool)
        ok = True
        for q in samples:
            pin.forwardKinematics(model, data, q)
            ref = np.array(pin.updateFramePlacement(model, data, arm.tool_frame_id).homogeneous)
            if np.abs(kin.fk(q) - ref).max() > tol:
                ok = False
                break
        if ok:
            return kin
    return None


# ---------------------------------------------------------------- batched DLS

def _skew_batch(v: np.ndarray) -> np.ndarray:
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def _log3_batch(rot: np.ndarray) -> np.ndarray:
    """Rotation vectors of a batch of rotation matrices (B, 3, 3) -> (B, 3)."""
    cos = np.clip((np.trace(rot, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    theta = np.arccos(cos)
    v = 0.5 * np.stack([rot[:, 2, 1] - rot[:, 1, 2], rot[:, 0, 2] - rot[:, 2, 0],
                        rot[:, 1, 0] - rot[:, 0, 1]], axis=1)  # sin(theta) * axis
    sin = np.sin(theta)
    small = theta < 1e-6
    factor = np.where(small, 1.0 + theta * theta / 6.0, theta / np.where(small, 1.0, sin))
    out = factor[:, None] * v
    near_pi = theta > math.pi - 1e-3
    if near_pi.any():  # sin(theta) ~ 0: take the axis from the symmetric part
        for b in np.flatnonzero(near_pi):
            sym = (rot[b] + rot[b].T) / 2.0 - cos[b] * np.eye(3)
            k = int(np.argmax(np.diag(sym)))
            axis = sym[:, k] / math.sqrt(max(sym[k, k], 1e-300))
            if axis @ v[b] < 0:
                axis = -axis
            out[b] = theta[b] * axis
    return out


class _Chain:
    """The joints from the root to the tool frame, for batched FK and Jacobians in numpy.

    Joint i's frame is ``parent @ placement_i @ motion(axis_i, q_i)`` (rotation about,
    or translation along, the unit ``axis_i`` of the joint frame); the tool is
    ``frame_last @ tool_placement``. Read from Pinocchio once (motion subspaces at
    q = 0), so it follows the model exactly (checked by the final Pinocchio FK).
    """

    def __init__(self, arm: SerialArm) -> None:
        import pinocchio as pin

        model = arm.model
        tool = model.frames[arm.tool_frame_id]
        path = []
        j = int(tool.parentJoint)
        while j > 0:
            path.append(j)
            j = int(model.parents[j])
        path.reverse()
        self.joints = path  # Pinocchio joint ids, root to tool
        data = model.createData()
        pin.computeJointJacobians(model, data, pin.neutral(model))
        self.placements = np.array([model.jointPlacements[j].homogeneous for j in path])
        self.q_index = np.array([model.joints[j].idx_q for j in path], dtype=np.int64)
        axes, revolute = [], []
        for j in path:
            col = np.array(pin.getJointJacobian(model, data, j, pin.LOCAL))[
                :, model.joints[j].idx_v]
            is_rev = bool(np.linalg.norm(col[3:]) > 0.5)
            axis = col[3:] if is_rev else col[:3]
            axes.append(axis / np.linalg.norm(axis))
            revolute.append(is_rev)
        self.axes = np.array(axes)
        self.revolute = np.array(revolute, dtype=bool)
        self.tool = np.array(tool.placement.homogeneous)
        self._eye = np.eye(3)
        self._k1 = _skew_batch(self.axes)
        self._k2 = self._k1 @ self._k1

    def fk_jacobian(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Tool rotations (B, 3, 3), positions (B, 3) and world-aligned Jacobians (B, 6, nq)."""
        batch = q.shape[0]
        rot = np.broadcast_to(np.eye(3), (batch, 3, 3))
        pos = np.zeros((batch, 3))
        origins, axes_world = [], []
        for k in range(len(self.q_index)):
            pos = pos + rot @ self.placements[k, :3, 3]
            rot = rot @ self.placements[k, :3, :3]
            z = rot @ self.axes[k]
            origins.append(pos)
            axes_world.append(z)
            value = q[:, self.q_index[k]]
            if self.revolute[k]:
                turn = (self._eye + np.sin(value)[:, None, None] * self._k1[k]
                        + (1.0 - np.cos(value))[:, None, None] * self._k2[k])
                rot = rot @ turn
            else:
                pos = pos + value[:, None] * z
        tool_pos = pos + rot @ self.tool[:3, 3]
        tool_rot = rot @ self.tool[:3, :3]
        jac = np.zeros((batch, 6, q.shape[1]))
        for k in range(len(self.q_index)):
            col = self.q_index[k]
            z = axes_world[k]
            if self.revolute[k]:
                r = tool_pos - origins[k]
                jac[:, 0, col] = z[:, 1] * r[:, 2] - z[:, 2] * r[:, 1]
                jac[:, 1, col] = z[:, 2] * r[:, 0] - z[:, 0] * r[:, 2]
                jac[:, 2, col] = z[:, 0] * r[:, 1] - z[:, 1] * r[:, 0]
                jac[:, 3:, col] = z
            else:
                jac[:, :3, col] = z
        return tool_rot, tool_pos, jac


# ---------------------------------------------------------------- spherical wrist

def _rot_batch(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotations (N, 3, 3) by ``angle`` (N,) about the fixed unit ``axis`` (Rodrigues)."""
    k1 = _skew_batch(axis)
    s = np.sin(angle)[:, None, None]
    c = np.cos(angle)[:, None, None]
    return np.eye(3) + s * k1 + (1.0 - c) * (k1 @ k1)


def _cos_sin_roots(a: np.ndarray, b: np.ndarray, c: np.ndarray,
                   tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """The angles t with a cos t + b sin t = c: (N, 2) roots and (N,) solvable mask.

    Solvable when |c| <= sqrt(a^2 + b^2) (1 + tol); a tangent case (|c| = r) gives two
    equal roots. A vanishing equation (a, b, c all below ``tol`` in size: every angle is
    a root) returns the representatives 0 and pi.
    """
    r = np.hypot(a, b)
    free = (r <= tol) & (np.abs(c) <= tol)
    ok = r > 1e-12
    ratio = np.where(ok, c / np.where(ok, r, 1.0), 2.0)
    ok &= np.abs(ratio) <= 1.0 + tol
    phase = np.arctan2(b, a)
    half = np.arccos(np.clip(ratio, -1.0, 1.0))
    phase = np.where(free, math.pi / 2, phase)
    half = np.where(free, math.pi / 2, half)
    return np.stack([phase + half, phase - half], axis=1), ok | free


def _plane_angle(axis: np.ndarray, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Angle (N,) of the rotation about the unit ``axis`` taking src's projection onto
    the plane normal to it to dst's (Paden-Kahan subproblem 1); 0 when a projection
    vanishes (the angle is then free)."""
    a = src - (src @ axis)[:, None] * axis
    b = dst - (dst @ axis)[:, None] * axis
    return np.arctan2(np.cross(a, b) @ axis, np.einsum("ij,ij->i", a, b))


@dataclass(frozen=True, eq=False)
class SphericalWristKinematics:
    """Product-of-exponentials description of a 6R arm with a spherical wrist.

    With the joint axes at q = 0 (unit directions ``axes[i]`` through ``points[i]``,
    world frame, measured with Pinocchio) the tool pose is
    ``tool(q) = exp(xi_1 q_1) ... exp(xi_6 q_6) home``. Required geometry (checked by
    :func:`spherical_wrist_kinematics`): axes 4, 5, 6 meet in the wrist centre
    ``wrist``; axes 2 and 3 are parallel; axis 1 is not parallel to them; axis 5 is
    parallel to neither 4 nor 6. Offsets anywhere else are allowed.

    Solution (up to 8): the wrist centre c = tool(q) home^-1 wrist depends on
    q_1..q_3 only. Its component along axis 2 is invariant under joints 2 and 3,
    which gives ``a cos q_1 + b sin q_1 = k`` (two shoulder branches); joint 3 sets
    the distance of c from axis 2 (two elbow branches), joint 2 the angle about it.
    The wrist rotation R_4 R_5 R_6 = G then gives q_4, q_5 by Paden-Kahan subproblem 2
    on axis 6 (two wrist branches) and q_6 by subproblem 1. At a wrist singularity
    (axes 4 and 6 aligned) only q_4 + q_6 is determined: q_4 = 0 is returned, one
    wrist branch. At a shoulder singularity (the wrist centre on axis 1, q_1 free) the
    representatives q_1 = 0 and pi are returned.

    Attributes:
        axes: (6, 3) unit joint axes at q = 0.
        points: (6, 3) a point on each axis at q = 0.
        wrist: (3,) the wrist centre at q = 0.
        home: 4x4 tool pose at q = 0.
    """

    axes: np.ndarray
    points: np.ndarray
    wrist: np.ndarray
    home: np.ndarray

    def __post_init__(self) -> None:
        shapes = {"axes": (6, 3), "points": (6, 3), "wrist": (3,), "home": (4, 4)}
        for name, shape in shapes.items():
            value = np.asarray(getattr(self, name), dtype=np.float64)
            if value.shape != shape or not np.all(np.isfinite(value)):
                raise ParameterError(f"SphericalWristKinematics.{name} must be a finite "
                                     f"{shape} array, got shape {value.shape}")
            value = value.copy()
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    def fk(self, q: Any) -> np.ndarray:
        """Tool poses (N, 4, 4) at joint vectors q (N, 6) or (6,) by the exponentials."""
        qs = np.atleast_2d(np.asarray(q, dtype=np.float64))
        out = np.broadcast_to(np.eye(4), (qs.shape[0], 4, 4)).copy()
        for i in range(6):
            rot = _rot_batch(self.axes[i], qs[:, i])
            step = np.zeros((qs.shape[0], 4, 4))
            step[:, :3, :3] = rot
            step[:, :3, 3] = self.points[i] - rot @ self.points[i]
            step[:, 3, 3] = 1.0
            out = out @ step
        return out @ self.home

    def solve_batch(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closed-form candidates for poses (P, 4, 4): (P, 8, 6) angles and (P, 8) mask.

        Candidate b = 4 s + 2 e + w (shoulder s, elbow e, wrist w branch) is valid when
        each step had a real root; angles are not wrapped. Nothing is checked by FK here.
        """
        w, p = self.axes, self.points
        n_pose = poses.shape[0]
        home_inv = _inv(self.home)
        c_tool = home_inv[:3, :3] @ self.wrist + home_inv[:3, 3]
        centre = poses[:, :3, :3] @ c_tool + poses[:, :3, 3]  # (P, 3) wrist centre
        # shoulder: (R1 u).(c - p1) = u.(wrist - p1), u = axis 2
        u = w[1]
        u_par = (u @ w[0]) * w[0]
        u_perp = u - u_par
        u_cross = np.cross(w[0], u)
        v = centre - p[0]
        q1, ok1 = _cos_sin_roots(v @ u_perp, v @ u_cross, u @ (self.wrist - p[0]) - v @ u_par)
        q1 = q1.reshape(-1)  # (2P,)
        ok = np.repeat(ok1, 2)
        rot1 = _rot_batch(w[0], q1)
        y = np.einsum("nji,nj->ni", rot1, np.repeat(v, 2, axis=0)) + p[0]  # R1^T (c - p1) + p1
        # elbow: |proj(R3 (wrist - p3) + p3 - p2)| = |proj(y - p2)| about axis 3
        w3 = w[2]
        arm3 = self.wrist - p[2]
        arm3 = arm3 - (arm3 @ w3) * w3
        d = p[1] - p[2]
        d = d - (d @ w3) * w3
        dy = y - p[1]
        dy = dy - (dy @ w3)[:, None] * w3
        delta2 = np.einsum("ij,ij->i", dy, dy)
        count = q1.shape[0]
        q3, ok3 = _cos_sin_roots(np.full(count, d @ arm3), np.full(count, d @ np.cross(w3, arm3)),
                                 0.5 * (arm3 @ arm3 + d @ d - delta2))
        q3 = q3.reshape(-1)  # (4P,)
        ok = np.repeat(ok & ok3, 2)
        q1 = np.repeat(q1, 2)
        y = np.repeat(y, 2, axis=0)
        rot3 = _rot_batch(w3, q3)
        z = rot3 @ (self.wrist - p[2]) + p[2]
        q2 = _plane_angle(w[1], z - p[1], y - p[1])
        # wrist: R4 R5 R6 = G = (R1 R2 R3)^T R_tool R_home^T
        r123 = _rot_batch(w[0], q1) @ _rot_batch(w[1], q2) @ rot3
        g = (np.transpose(r123, (0, 2, 1)) @ np.repeat(poses[:, :3, :3], 4, axis=0)
             @ self.home[:3, :3].T)
        w4, w5, w6 = w[3], w[4], w[5]
        target = g @ w6  # R4 R5 w6 = G w6
        c45 = float(w4 @ w5)
        cross45 = np.cross(w4, w5)
        den = 1.0 - c45 * c45
        alpha = (target @ w4 - c45 * (w5 @ w6)) / den
        beta = (w5 @ w6 - c45 * (target @ w4)) / den
        gamma2 = ((1.0 - alpha * alpha - beta * beta - 2.0 * alpha * beta * c45)
                  / (cross45 @ cross45))
        ok &= gamma2 >= -1e-9
        gamma = np.sqrt(np.maximum(gamma2, 0.0))
        mid = alpha[:, None] * w4 + beta[:, None] * w5
        # wrist singularity: G w6 along axis 4, so R5 w6 is too and q4 is free: q4 = 0
        singular = np.linalg.norm(np.cross(target, w4), axis=1) < 1e-9
        q4s, q5s, q6s = [], [], []
        for sign in (1.0, -1.0):
            zw = np.where(singular[:, None], target, mid + sign * gamma[:, None] * cross45)
            q5 = _plane_angle(w5, np.broadcast_to(w6, zw.shape), zw)
            q4 = np.where(singular, 0.0, _plane_angle(w4, zw, target))
            rest = (np.transpose(_rot_batch(w4, q4) @ _rot_batch(w5, q5), (0, 2, 1)) @ g)
            x = np.cross(w6, w4 if abs(w6 @ w4) < 0.9 else w5)
            x /= np.linalg.norm(x)
            q6 = _plane_angle(w6, np.broadcast_to(x, zw.shape), rest @ x)
            q4s.append(q4)
            q5s.append(q5)
            q6s.append(q6)
        sol = np.empty((count * 2, 2, 6))
        for k, arr in enumerate((q1, q2, q3)):
            sol[:, :, k] = arr[:, None]
        sol[:, :, 3] = np.stack(q4s, axis=1)
        sol[:, :, 4] = np.stack(q5s, axis=1)
        sol[:, :, 5] = np.stack(q6s, axis=1)
        valid = np.stack([ok, ok & ~singular], axis=1)  # one wrist branch when singular
        return sol.reshape(n_pose, 8, 6), valid.reshape(n_pose, 8)

    def solve(self, pose: np.ndarray) -> np.ndarray:
        """All (<= 8) closed-form candidates for one 4x4 pose, angles in (-pi, pi]."""
        sol, valid = self.solve_batch(np.asarray(pose, dtype=np.float64)[None])
        out = sol[0][valid[0]]
        return (out + math.pi) % TWO_PI - math.pi


def _line_point(axes: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, float]:
    """The point closest to lines (axis, point) in least squares, and its largest distance."""
    lhs = np.zeros((3, 3))
    rhs = np.zeros(3)
    for a, p in zip(axes, points, strict=True):
        proj = np.eye(3) - np.outer(a, a)
        lhs += proj
        rhs += proj @ p
    x = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    dist = max(float(np.linalg.norm((np.eye(3) - np.outer(a, a)) @ (x - p)))
               for a, p in zip(axes, points, strict=True))
    return x, dist


def spherical_wrist_kinematics(arm: SerialArm, *, checks: int = 20, tol: float = 1e-9,
                               geometry_tol: float = 1e-7) -> SphericalWristKinematics | None:
    """The spherical-wrist description of ``arm`` if it has that geometry, else None.

    Reads the joint axes at q = 0 from Pinocchio; requires six revolute joints in one
    chain to the tool frame, axes 4-6 meeting in a point and axes 2, 3 parallel (both
    within ``geometry_tol``), axis 1 not parallel to axis 2 and axis 5 parallel to
    neither 4 nor 6. Accepted only when, at ``checks`` random configurations within
    [-pi, pi] (seed 0), the exponentials' FK matches Pinocchio's to ``tol`` and the
    closed form, solved for that pose, returns the configuration (modulo 2 pi) among
    its candidates.
    """
    import pinocchio as pin

    model = arm.model
    if arm.nq != 6 or not arm.revolute.all():
        return None
    chain = _Chain(arm)
    if len(chain.q_index) != 6 or not np.array_equal(chain.q_index, np.arange(6)):
        return None
    if not chain.revolute.all():
        return None
    data = model.createData()
    q0 = np.zeros(6)
    pin.forwardKinematics(model, data, q0)
    axes = np.array([np.array(data.oMi[j].rotation) @ chain.axes[k]
                     for k, j in enumerate(chain.joints)])
    points = np.array([np.array(data.oMi[j].translation) for j in chain.joints])
    wrist, miss = _line_point(axes[3:], points[3:])
    if miss > geometry_tol:
        return None
    if np.linalg.norm(np.cross(axes[1], axes[2])) > geometry_tol:
        return None
    if min(float(np.linalg.norm(np.cross(axes[0], axes[1]))),
           float(np.linalg.norm(np.cross(axes[3], axes[4]))),
           float(np.linalg.norm(np.cross(axes[4], axes[5])))) < 1e-6:
        return None
    home = np.array(pin.updateFramePlacement(model, data, arm.tool_frame_id).homogeneous)
    kin = SphericalWristKinematics(axes, points, wrist, home)
    rng = np.random.default_rng(0)
    samples = rng.uniform(-math.pi, math.pi, size=(checks, 6))
    refs = []
    for q in samples:
        pin.forwardKinematics(model, data, q)
        refs.append(np.array(pin.updateFramePlacement(model, data, arm.tool_frame_id).homogeneous))
    if np.abs(kin.fk(samples) - np.array(refs)).max() > tol:
        return None
    sols, valid = kin.solve_batch(np.array(refs))
    for q, cand, ok in zip(samples, sols, valid, strict=True):
        diff = np.abs(cand[ok] - q) % TWO_PI
        diff = np.minimum(diff, TWO_PI - diff)
        if diff.size == 0 or diff.max(axis=1).min() > 1e-6:
            return None
    return kin


# ---------------------------------------------------------------- solver

class IKSolver:
    """All IK solutions of one arm; see the module doc. Thread-safe (per-thread data).

    Attributes:
        arm: the :class:`SerialArm`.
        params: :class:`IKParams`.
        ur: the verified UR DH description, or None.
        spherical: the verified spherical-wrist description (when ``ur`` is None), or None.
        method: the method :meth:`solve` uses (``"closed_form"`` or ``"dls"``).
    """

    def __init__(self, arm: SerialArm, params: IKParams | None = None) -> None:
        self.arm = arm
        self.params = params if params is not None else IKParams()
        if not isinstance(self.params, IKParams):
            raise ParameterError(f"params must be IKParams, got {type(self.params).__name__}")
        self.ur = ur_kinematics(arm) if self.params.method != "dls" else None
        self.spherical = (spherical_wrist_kinematics(arm)
                          if self.params.method != "dls" and self.ur is None else None)
        if self.params.method == "closed_form" and self.ur is None and self.spherical is None:
            raise ParameterError(f"IKParams.method='closed_form' but {arm.name} has no closed "
                                 "form (the UR family and 6R arms with a spherical wrist have "
                                 "one); use 'auto' or 'dls'")
        closed = self.ur is not None or self.spherical is not None
        self.method = "closed_form" if closed else "dls"
        lim = arm.limits
        lo = np.where(arm.revolute, np.maximum(lim.lower, -math.pi), lim.lower)
        hi = np.where(arm.revolute, np.minimum(lim.upper, math.pi), lim.upper)
        self._sample_lo, self._sample_hi = lo, hi
        self._chain = _Chain(arm)

    def __repr__(self) -> str:
        return f"IKSolver({self.arm.name!r}, method={self.method!r})"

    # -- pieces

    def pose_error(self, q: np.ndarray, pose: np.ndarray) -> tuple[float, float]:
        """(position m, rotation rad) error of the tool at q from ``pose`` (Pinocchio FK)."""
        import pinocchio as pin

        reached = self.arm.fk_se3(q)
        err = pin.log6(reached.actInv(pin.SE3(pose))).vector
        return float(np.linalg.norm(err[:3])), float(np.linalg.norm(err[3:]))

    def _newton(self, q: np.ndarray, target: Any, max_iter: int, damping: float) -> tuple[
            np.ndarray, float]:
        """DLS iterations from q; returns (q, final error: max abs component of the log error).

        Stops when the error is below 1e-11, or gives up when it has not halved over
        the last ``_STALL`` iterations (a start stuck at a singularity or outside
        the workspace).
        """
        import pinocchio as pin

        model, data = self.arm.model, self.arm.data
        fid = self.arm.tool_frame_id
        eye = np.eye(6)
        err_norm = math.inf
        history: list[float] = []
        for _ in range(max_iter):
            pin.computeJointJacobians(model, data, q)  # also runs forward kinematics
            current = pin.updateFramePlacement(model, data, fid)
            # e = log6(target^-1 current); a LOCAL twist J dq moves it by Jlog6(.) J dq
            rel = target.actInv(current)
            err = pin.log6(rel).vector
            err_norm = float(np.abs(err).max())
            if err_norm < 1e-11:
                break
            history.append(err_norm)
            if len(history) > _STALL and err_norm > 0.5 * history[-_STALL - 1]:
                break
            jac = pin.getFrameJacobian(model, data, fid, pin.LOCAL)
            jerr = pin.Jlog6(rel) @ jac
            step = -jerr.T @ np.linalg.solve(jerr @ jerr.T + damping * damping * eye, err)
            scale = float(np.abs(step).max())
            if scale > self.params.max_step:
                step *= self.params.max_step / scale
            q = q + step
        return q, err_norm

    def _accepts(self, q: np.ndarray, pose: np.ndarray) -> bool:
        dp, dr = self.pose_error(q, pose)
        return dp <= self.params.accept_tol and dr <= self.params.accept_tol

    def _alternatives(self, q: np.ndarray) -> list[np.ndarray]:
        """Every q + 2 pi k (revolute joints) inside the limits; [] if none."""
        lim = self.arm.limits
        eps = 1e-9
        choices: list[list[float]] = []
        for j in range(self.arm.nq):
            if not self.arm.revolute[j]:
                if lim.lower[j] - eps <= q[j] <= lim.upper[j] + eps:
                    choices.append([float(q[j])])
                else:
                    return []
                continue
            kmin = math.ceil((lim.lower[j] - eps - q[j]) / TWO_PI)
            kmax = math.floor((lim.upper[j] + eps - q[j]) / TWO_PI)
            values = [float(q[j] + TWO_PI * k) for k in range(kmin, kmax + 1)]
            if not values:
                return []
            if not self.params.wrap_alternatives:
                values = [min(values, key=abs)]
            choices.append(values)
        return [np.clip(np.array(c), lim.lower, lim.upper)
                for c in itertools.product(*choices)]

    def _canonical(self, q: np.ndarray) -> np.ndarray | None:
        """q with each revolute joint shifted by the multiple of 2 pi closest to 0 that
        keeps it inside the limits; None when some joint cannot be (or a prismatic is out).
        """
        lim = self.arm.limits
        eps = 1e-9
        out = q.copy()
        rev = self.arm.revolute
        kmin = np.ceil((lim.lower - eps - q) / TWO_PI)
        kmax = np.floor((lim.upper + eps - q) / TWO_PI)
        k = np.clip(np.round(-q / TWO_PI), kmin, kmax)
        out[rev] = q[rev] + TWO_PI * k[rev]
        inside = (out >= lim.lower - eps) & (out <= lim.upper + eps)
        if not inside.all():
            return None
        return np.clip(out, lim.lower, lim.upper)

    def _distinct(self, candidates: list[np.ndarray]) -> list[np.ndarray]:
        """Drop candidates equal (modulo 2 pi on revolute joints) to an earlier one."""
        kept: list[np.ndarray] = []
        rev = self.arm.revolute
        for q in candidates:
            duplicate = False
            for other in kept:
                diff = np.abs(q - other)
                diff[rev] = np.minimum(diff[rev] % TWO_PI, TWO_PI - diff[rev] % TWO_PI)
                if diff.max() < self.params.dedup_tol:
                    duplicate = True
                    break
            if not duplicate:
                kept.append(q)
        return kept

    def _raw(self, pose: np.ndarray, rng: np.random.Generator) -> list[np.ndarray]:
        """Unpolished candidate solutions by the solver's method."""
        if self.ur is not None:
            return list(self.ur.solve(pose))
        if self.spherical is not None:
            return list(self.spherical.solve(pose))
        p = self.params
        q = rng.uniform(self._sample_lo, self._sample_hi, size=(p.starts, self.arm.nq))
        return list(self._batch_dls(q, pose))

    def _batch_dls(self, q: np.ndarray, pose: np.ndarray) -> np.ndarray:
        """Damped least squares from every row of q at once; returns the converged rows.

        Error: (p_target - p, log3(R_target R^T)) in the world frame; a row stops when
        the error is below 1e-11 (converged) or has not halved over ``_STALL``
        iterations (stuck), or after ``max_iter`` iterations.
        """
        p = self.params
        chain = self._chain
        q = q.copy()
        err_max = np.full(q.shape[0], np.inf)
        rows = np.arange(q.shape[0])  # the rows still iterating
        history = np.full((p.max_iter, q.shape[0]), np.inf)
        eye = np.eye(6)
        for it in range(p.max_iter):
            sub = q[rows]
            tool_rot, tool_pos, jac = chain.fk_jacobian(sub)
            err = np.empty((len(rows), 6))
            err[:, :3] = pose[:3, 3] - tool_pos
            err[:, 3:] = _log3_batch(pose[:3, :3] @ np.transpose(tool_rot, (0, 2, 1)))
            err_max[rows] = np.abs(err).max(axis=1)
            history[it, rows] = err_max[rows]
            keep = err_max[rows] >= 1e-11
            if it >= _STALL:
                keep &= err_max[rows] <= 0.5 * history[it - _STALL, rows]
            if not keep.any():
                break
            rows, sub, err, jac = rows[keep], sub[keep], err[keep], jac[keep]
            jt = np.transpose(jac, (0, 2, 1))
            lhs = jac @ jt + (p.damping * p.damping) * eye
            step = (jt @ np.linalg.solve(lhs, err[:, :, None]))[:, :, 0]
            scale = np.abs(step).max(axis=1)
            step *= np.minimum(1.0, p.max_step / np.maximum(scale, 1e-300))[:, None]
            q[rows] = sub + step
        return q[err_max < 1e-8]

    def _canonical_batch(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_canonical` of every row of q (m, nq): (shifted rows, inside mask)."""
        lim = self.arm.limits
        eps = 1e-9
        rev = self.arm.revolute
        kmin = np.ceil((lim.lower - eps - q) / TWO_PI)
        kmax = np.floor((lim.upper + eps - q) / TWO_PI)
        k = np.clip(np.round(-q / TWO_PI), kmin, kmax)
        out = np.where(rev, q + TWO_PI * k, q)
        inside = np.asarray(((out >= lim.lower - eps) & (out <= lim.upper + eps)).all(axis=1))
        return np.clip(out, lim.lower, lim.upper), inside

    def _alternatives_batch(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_alternatives` of every row of q (m, nq), canonical rows inside the limits.

        Returns (rows, owner): the alternatives of row i are the rows with owner i, in
        the order :meth:`_alternatives` gives them (lexicographic, joint 1 first).
        """
        owner = np.arange(q.shape[0])
        if not self.params.wrap_alternatives or q.shape[0] == 0:
            return q, owner
        lim = self.arm.limits
        eps = 1e-9
        rows = q
        for j in np.flatnonzero(self.arm.revolute):
            span = int(math.ceil((lim.upper[j] - lim.lower[j]) / TWO_PI)) + 1
            parts_q, parts_o = [], []
            for k in range(-span, span + 1):
                value = rows[:, j] + TWO_PI * k
                keep = (value >= lim.lower[j] - eps) & (value <= lim.upper[j] + eps)
                moved = rows[keep].copy()
                moved[:, j] = value[keep]
                parts_q.append(moved)
                parts_o.append(owner[keep])
            rows, owner = np.concatenate(parts_q), np.concatenate(parts_o)
        order = np.lexsort(tuple(rows[:, j] for j in range(rows.shape[1] - 1, -1, -1))
                           + (owner,))
        return np.clip(rows[order], lim.lower, lim.upper), owner[order]

    def _closed_form_canonical(self, poses: np.ndarray) -> list[np.ndarray]:
        """Canonical distinct accepted solutions of each pose (P, 4, 4), closed form batched.

        Candidates of the closed form (UR or spherical wrist) are shifted into the limits,
        de-duplicated, and accepted by the chain's FK (a copy of Pinocchio's); a
        candidate that misses by more than ``accept_tol`` is polished by Newton steps
        on Pinocchio's FK as in :meth:`solve_canonical`, dropped if it still misses.
        """
        import pinocchio as pin

        kinematics = self.ur if self.ur is not None else self.spherical
        assert kinematics is not None
        n_pose, nq = poses.shape[0], self.arm.nq
        sol, valid = kinematics.solve_batch(poses)
        flat, inside = self._canonical_batch(sol.reshape(-1, nq))
        sol = flat.reshape(n_pose, 8, nq)
        valid &= inside.reshape(n_pose, 8)
        diff = np.abs(sol[:, :, None, :] - sol[:, None, :, :]) % TWO_PI
        diff = np.where(self.arm.revolute, np.minimum(diff, TWO_PI - diff),
                        np.abs(sol[:, :, None, :] - sol[:, None, :, :]))
        same = (diff.max(axis=3) < self.params.dedup_tol) & valid[:, None, :]
        same &= np.tril(np.ones((8, 8), dtype=bool), -1)  # an earlier valid candidate
        valid &= ~same.any(axis=2)
        pose_of, branch = np.nonzero(valid)
        cand = sol[pose_of, branch]
        rot, pos, _ = self._chain.fk_jacobian(cand)
        target = poses[pose_of]
        dp = np.linalg.norm(target[:, :3, 3] - pos, axis=1)
        dr = np.linalg.norm(_log3_batch(target[:, :3, :3] @ np.transpose(rot, (0, 2, 1))), axis=1)
        good = (dp <= self.params.accept_tol) & (dr <= self.params.accept_tol)
        out: list[list[np.ndarray]] = [[] for _ in range(n_pose)]
        polished_any = set()
        for row in range(cand.shape[0]):
            q = cand[row]
            if not good[row]:
                pose4 = target[row]
                polished = self._canonical(self._newton(q, pin.SE3(pose4), 5, 1e-6)[0])
                if polished is None or not self._accepts(polished, pose4):
                    continue
                q = polished
                polished_any.add(int(pose_of[row]))
            out[int(pose_of[row])].append(q)
        result = []
        for i, qs in enumerate(out):
            if i in polished_any:
                qs = self._distinct(qs)
            result.append(np.array(qs) if qs else np.zeros((0, nq)))
        return result

    # -- public

    def solve_canonical(self, pose: Any, *, seed: Seed = 0) -> np.ndarray:
        """Distinct solutions modulo 2 pi, each inside the limits, without alternatives.

        Returns a (k, nq) array; revolute joints are shifted by the multiple of 2 pi
        closest to 0 that keeps them inside the limits.
        """
        import pinocchio as pin

        arr = as_pose_array(pose)
        if arr.shape[0] != 1:
            raise ParameterError(f"solve takes one 4x4 pose, got {arr.shape[0]}")
        pose4 = arr[0]
        if not np.all(np.isfinite(pose4)):
            raise ParameterError("pose must be finite")
        _check_seed(seed)
        if self.spherical is not None:
            return self._closed_form_canonical(pose4[None])[0]
        rng = np.random.default_rng(seed)
        target = pin.SE3(pose4)
        candidates = []
        for q in self._raw(pose4, rng):
            canon = self._canonical(q)
            if canon is not None:
                candidates.append(canon)
        kept = []
        for q in self._distinct(candidates):
            if not self._accepts(q, pose4):  # polish by Newton steps on Pinocchio's FK
                polished = self._canonical(self._newton(q, target, 5, 1e-6)[0])
                if polished is None or not self._accepts(polished, pose4):
                    continue
                q = polished
            kept.append(q)
        return np.array(kept) if kept else np.zeros((0, self.arm.nq))

    def solve(self, pose: Any, *, seed: Seed = 0) -> np.ndarray:
        """Every distinct solution for one 4x4 pose, with +-2 pi alternatives: (m, nq)."""
        canon = self.solve_canonical(pose, seed=seed)
        out: list[np.ndarray] = []
        for q in canon:
            out.extend(self._alternatives(q))
        return np.array(out) if out else np.zeros((0, self.arm.nq))

    def solve_targets(self, poses: Sequence[Any], *, seed: int | None = 0) -> TargetSolutions:
        """Solutions of every candidate pose of every target.

        Args:
            poses: one (k_i, 4, 4) array of candidate poses per target (as
                :attr:`~subtask_opt.arm.poses.Targets.poses` holds them).
            seed: candidate j of target i uses the generator ``default_rng([seed, i, j])``
                (None: fresh entropy), so a target's solutions do not depend on the others.
        """
        if isinstance(poses, np.ndarray) or not isinstance(poses, Sequence):
            raise ParameterError("poses must be a sequence of (k, 4, 4) pose arrays, one per "
                                 f"target; got {type(poses).__name__}")
        if seed is not None:
            require_int("IKSolver", "seed", seed, 0)
        if self.ur is not None or self.spherical is not None:
            return self._solve_targets_batched(poses)
        from subtask_opt.base.stop import check_time_limit

        configurations, indices = [], []
        for i, block in enumerate(poses):
            check_time_limit(f"in the IK (target {i + 1} of {len(poses)})")
            sols: list[np.ndarray] = []
            idx: list[int] = []
            for j, pose in enumerate(block):
                sub_seed: Seed = None if seed is None else [seed, i, j]
                found = self.solve(pose, seed=sub_seed)
                sols.extend(found)
                idx.extend([j] * len(found))
            configurations.append(np.array(sols) if sols else np.zeros((0, self.arm.nq)))
            indices.append(np.array(idx, dtype=np.int64))
        return TargetSolutions(configurations=tuple(configurations), pose_index=tuple(indices),
                               method=self.method)

    def _solve_targets_batched(self, poses: Sequence[Any]) -> TargetSolutions:
        """:meth:`solve_targets` for an arm with a closed form (UR or spherical wrist): every
        candidate pose of every target in one numpy batch, no per-target Python loop."""
        nq = self.arm.nq
        blocks = [np.asarray(block, dtype=np.float64) for block in poses]
        sizes = [b.shape[0] for b in blocks]
        stacked_poses = np.concatenate(blocks) if sum(sizes) else np.zeros((0, 4, 4))
        if not np.all(np.isfinite(stacked_poses)):
            raise ParameterError("pose must be finite")
        canon = self._closed_form_canonical(stacked_poses)
        counts = np.array([c.shape[0] for c in canon], dtype=np.int64)
        stacked = np.concatenate(canon) if counts.sum() else np.zeros((0, nq))
        pose_of = np.repeat(np.arange(len(canon)), counts)
        rows, owner = self._alternatives_batch(stacked)
        row_pose = pose_of[owner]  # sorted by pose (owner is sorted, pose_of non-decreasing)
        target_start = np.concatenate([[0], np.cumsum(sizes)])
        configurations, indices = [], []
        bounds = np.searchsorted(row_pose, target_start)
        for i in range(len(blocks)):
            lo, hi = bounds[i], bounds[i + 1]
            configurations.append(np.ascontiguousarray(rows[lo:hi]))
            indices.append((row_pose[lo:hi] - target_start[i]).astype(np.int64))
        return TargetSolutions(configurations=tuple(configurations), pose_index=tuple(indices),
                               method=self.method)
