"""Figures and animation of an executed tour (:class:`subtask_opt.arm.trajectory.Trajectory`).

* :func:`plot_joint_profiles` - joint positions, velocities and accelerations
  against time, with the limits;
* :func:`plot_executed_path` - the tip's travelled path over the workspace,
  straight lines and joint moves told apart;
* :func:`animate_tour` - a GIF (Pillow writer) of the arm executing the tour,
  with the subtasks and the path travelled so far.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from subtask_opt.base.errors import InputDataError, require_int, require_positive
from subtask_opt.base.progress import progress_bar
from subtask_opt.kinematics._kernels import fk_batch
from subtask_opt.plotting.sequencing import plot_workspace

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from subtask_opt.arm.planar_problem import PlanarProblem
    from subtask_opt.arm.trajectory import Trajectory


def plot_joint_profiles(trajectory: Trajectory, *, dt: float = 0.005,
                        fig: Figure | None = None) -> Figure:
    """Three stacked panels: q, q_dot, q_ddot of both joints over the tour, limits dashed.

    ``dt`` is the sampling step (s), in the range of :meth:`Trajectory.sample`.
    """
    import matplotlib.pyplot as plt

    s = trajectory.sample(dt)
    jl = trajectory.arm.joint_limits
    if fig is None:
        fig = plt.figure(figsize=(9, 7))
    axes = fig.subplots(3, 1, sharex=True)
    colours = ("tab:blue", "tab:orange")
    for ax, values, label, lo, hi in (
            (axes[0], s.q, "q [rad]", jl.lower, jl.upper),
            (axes[1], s.qd, "dq/dt [rad/s]", -jl.velocity, jl.velocity),
            (axes[2], s.qdd, "d2q/dt2 [rad/s^2]", -jl.acceleration, jl.acceleration)):
        for a in range(2):
            ax.plot(s.t, values[:, a], color=colours[a], lw=1.0, label=f"joint {a + 1}")
            for bound in (lo[a], hi[a]):
                ax.axhline(bound, color=colours[a], ls="--", lw=0.7, alpha=0.6)
        ax.set_ylabel(label)
        for leg in trajectory.legs:
            if leg.kind == "line":
                ax.axvspan(leg.start, leg.start + leg.duration, color="0.9", lw=0, zorder=0)
    axes[0].plot([], [], color="0.3", ls="--", lw=0.7, label="limits")
    axes[0].fill_between([], [], color="0.9", label="straight-line leg")
    axes[0].legend(loc="upper right", fontsize=8, ncol=4)
    axes[0].set_title(_title(trajectory))
    axes[2].set_xlabel("t [s]")
    fig.tight_layout()
    return fig


def _title(trajectory: Trajectory) -> str:
    """Robot, time model, N and the executed (and predicted) tour time."""
    return (f"{trajectory.arm.name}, {trajectory.time_model} model, N = {len(trajectory.legs)}: "
            f"executed {trajectory.duration:.3f} s (predicted {trajectory.predicted_time:.3f} s)")


def plot_executed_path(problem: PlanarProblem, trajectory: Trajectory, *,
                       dt: float = 0.005, ax: Axes | None = None) -> Axes:
    """The tip's path over the workspace: straight legs solid, joint moves dashed."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(7, 6))
    arm = trajectory.arm
    plot_workspace(ax, arm, label=False)
    for leg in trajectory.legs:
        t = np.arange(0.0, leg.duration + dt, dt)
        q, _, _ = leg.states(t)
        xy = fk_batch(arm.kinematics, np.ascontiguousarray(q))[:, :2]
        style = "-" if leg.kind == "line" else "--"
        colour = "tab:red" if leg.from_config == leg.to_config else "tab:purple"
        ax.plot(xy[:, 0], xy[:, 1], style, color=colour, lw=1.2, zorder=3)
    pts = problem.subtasks.points
    ax.scatter(pts[:, 0], pts[:, 1], s=24, color="k", zorder=5, label="subtask")
    ax.fill([], [], color="tab:blue", alpha=0.12, label="reachable within joint limits")
    ax.plot([], [], "-", color="tab:red", label="straight line")
    ax.plot([], [], "--", color="tab:red", label="joint move")
    ax.plot([], [], "--", color="tab:purple", label="joint move, elbow change")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("executed tour: " + _title(trajectory), fontsize=10)
    return ax


def animate_tour(problem: PlanarProblem, trajectory: Trajectory, path: str | Path, *,
                 fps: int = 15, speed: float = 1.0, max_frames: int = 150,
                 dpi: int = 72, progress: bool = False) -> Path:
    """Write a GIF of the arm executing the tour.

    Args:
        fps: frames per second of the GIF.
        speed: playback speed (2.0 plays twice as fast as real time).
        max_frames: upper bound on frames; the playback speeds up to respect it.
        dpi: resolution of the frames (each is 5 x 5 inches).
        progress: show a progress bar on stderr (rendering takes ~50 ms a frame).
    """
    require_int("animate_tour", "fps", fps, 1)
    require_positive("animate_tour", "speed", speed)
    require_int("animate_tour", "max_frames", max_frames, 2)
    require_int("animate_tour", "dpi", dpi, 10)
    path = Path(path)
    if path.suffix.lower() != ".gif":
        raise InputDataError(f"animation file must end in .gif, got {path.name!r}")
    if not path.parent.exists():
        raise InputDataError(f"cannot write {path}: directory {path.parent} does not exist")
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.figure import Figure

    arm = trajectory.arm
    n_frames = int(min(max_frames, max(2, trajectory.duration * fps / speed)))
    t = np.linspace(0.0, trajectory.duration, n_frames)
    q, _, _ = trajectory.states(t)
    links = np.array([arm.link_points(qk) for qk in q])  # (T, 3, 2)
    fig = Figure(figsize=(5.5, 5.5))
    ax = fig.add_subplot()
    plot_workspace(ax, arm, resolution=200)
    pts = problem.subtasks.points
    ax.scatter(pts[:, 0], pts[:, 1], s=20, color="k", zorder=5, label="subtask")
    trail, = ax.plot([], [], "-", color="tab:red", lw=1.2, zorder=3, label="tip path so far")
    body, = ax.plot([], [], "o-", color="0.25", lw=3, ms=5, zorder=6, label="arm")
    label = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=9)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(loc="lower right", fontsize=7)
    ax.set_title(_title(trajectory), fontsize=8)
    fig.tight_layout()

    def draw(k: int):
        trail.set_data(links[: k + 1, 2, 0], links[: k + 1, 2, 1])
        body.set_data(links[k, :, 0], links[k, :, 1])
        label.set_text(f"t = {t[k]:.2f} / {trajectory.duration:.2f} s")
        return trail, body, label

    anim = FuncAnimation(fig, draw, frames=n_frames, blit=False)
    with progress_bar(progress, total=n_frames, desc="animation", unit="frame") as bar:
        try:
            anim.save(str(path), writer=PillowWriter(fps=fps), dpi=dpi,
                      progress_callback=lambda i, n: bar.update(1))
        except OSError as exc:
            raise InputDataError(f"cannot write animation {path}: {exc}") from None
    return path


__all__ = ["animate_tour", "plot_executed_path", "plot_joint_profiles"]
