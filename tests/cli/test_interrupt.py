"""Ctrl-C during ``solve`` or ``batch``: exit 130, one line on stderr, no traceback, no
JSON (whole or partial) and no temporary file left (issue 30, item 2).

The signal goes to the whole process group, as a terminal's Ctrl-C does, so the batch's
worker processes receive it too and must stay quiet. It is sent once the command is
inside its run (its pid has been alive for a while and its kernels are loaded), so the
test does not depend on how fast the machine is.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from subtask_opt.arm.tasks import random_subtasks, save_subtasks
from subtask_opt.kinematics.planar import load_planar_arm

ROOT = Path(__file__).resolve().parents[2]


def _as_a_shell_starts_it() -> None:
    """Ctrl-C at its default action in the command, as a shell starts it: a process that
    ignores SIGINT passes that on to what it starts, and a test runner's worker may have
    inherited it (the command would then never see the Ctrl-C)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _catches_sigint(pid: int) -> bool:
    """Whether process ``pid`` has a SIGINT handler (Linux; True where it cannot tell)."""
    status = Path(f"/proc/{pid}/status")
    if not status.exists():
        return True
    caught = next(int(line.split()[1], 16) for line in status.read_text().splitlines()
                  if line.startswith("SigCgt:"))
    return bool(caught >> (signal.SIGINT - 1) & 1)


def _interrupt(argv: list[str], cwd: Path, after_s: float) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    proc = subprocess.Popen([sys.executable, "-m", "subtask_opt.cli", *argv], cwd=cwd,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True,
                            preexec_fn=_as_a_shell_starts_it)
    time.sleep(after_s)
    assert proc.poll() is None, proc.communicate()
    assert _catches_sigint(proc.pid), "the command does not handle Ctrl-C"
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    return subprocess.CompletedProcess(argv, proc.returncode, out, err)


def _check(done: subprocess.CompletedProcess, folder: Path) -> None:
    lines = [ln for ln in done.stderr.splitlines()
             if ln.strip() and not ln.startswith("subtask-opt: compiling")]
    assert done.returncode == 130, done.stderr
    assert "Traceback" not in done.stderr
    assert len(lines) == 1 and "interrupted" in lines[0], done.stderr
    assert not (folder / "out.json").exists()
    assert not [p for p in folder.rglob("*") if ".part" in p.name]


def test_ctrl_c_during_solve(tmp_path):
    argv = ["solve", "--case", "random30", "--time-limit", "300", "--no-improvement",
            "1000000", "--max-generations", "10000000", "--no-progress", "--json",
            str(tmp_path / "out.json")]
    _check(_interrupt(argv, tmp_path, after_s=15.0), tmp_path)


@pytest.mark.parametrize("workers", ["0", "2"])
def test_ctrl_c_during_batch(tmp_path, workers):
    arm = load_planar_arm("planar_2r")
    files = []
    for i in range(4):
        save_subtasks(random_subtasks(arm, 30, seed=i), tmp_path / f"p{i}.csv")
        files.append(str(tmp_path / f"p{i}.csv"))
    argv = ["batch", *files, "--workers", workers, "--time-limit", "120",
            "--no-improvement", "1000000", "--no-progress", "--json",
            str(tmp_path / "out.json")]
    _check(_interrupt(argv, tmp_path, after_s=25.0), tmp_path)
