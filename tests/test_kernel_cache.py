"""The kernel cache folder follows the kernel sources: any edit selects a fresh folder."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numba
import pytest

from subtask_opt import _kernel_cache
from tests.conftest import PROJECT_ROOT, REDUCED


def _tree(root: Path, body: str) -> None:
    (root / "ga").mkdir(parents=True, exist_ok=True)
    (root / "ga" / "kernel.py").write_text(f"@njit(cache=True)\ndef f(x):\n    {body}\n")
    (root / "plain.py").write_text("x = 1\n")


def test_hash_changes_with_any_kernel_source_and_ignores_other_files(tmp_path, monkeypatch):
    monkeypatch.setattr(_kernel_cache, "PACKAGE_DIR", tmp_path)
    _tree(tmp_path, "return x")
    first = _kernel_cache.source_hash()
    assert _kernel_cache.source_hash() == first
    (tmp_path / "plain.py").write_text("x = 2\n")  # no kernel in it
    assert _kernel_cache.source_hash() == first
    _tree(tmp_path, "return x + 1000")  # the stale-cache experiment, in miniature
    assert _kernel_cache.source_hash() != first


def test_cache_root_honours_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("SUBTASK_OPT_CACHE_DIR", str(tmp_path / "c"))
    assert _kernel_cache.cache_root() == tmp_path / "c"
    monkeypatch.delenv("SUBTASK_OPT_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert _kernel_cache.cache_root() == tmp_path / "x" / "subtask_opt"


def test_numba_uses_the_hashed_folder() -> None:
    import numba

    assert numba.config.CACHE_DIR == str(_kernel_cache.CACHE_DIR)
    assert _kernel_cache.CACHE_DIR.name == f"kernels-{_kernel_cache.source_hash()}"


@pytest.mark.parametrize("group", ["a-group"])
def test_warm_markers(tmp_path, monkeypatch, group):
    monkeypatch.setattr(_kernel_cache, "CACHE_DIR", tmp_path)
    assert not _kernel_cache.is_warm(group)
    _kernel_cache.mark_warm(group)
    assert _kernel_cache.is_warm(group)


def test_a_cold_group_is_announced_once_per_process_even_into_a_pipe(tmp_path, monkeypatch,
                                                                     capsys):
    monkeypatch.setattr(_kernel_cache, "CACHE_DIR", tmp_path)
    monkeypatch.setattr(_kernel_cache, "_announced", False)
    with _kernel_cache.compiling("first", "the first kernels"):
        said = capsys.readouterr().err  # before the (long) block ends
    assert said.count("\n") == 1 and "compiling the first kernels (numba" in said
    assert str(tmp_path) in said and _kernel_cache.is_warm("first")
    with _kernel_cache.compiling("second", "the second kernels"):
        pass
    assert capsys.readouterr().err == "" and _kernel_cache.is_warm("second")


def test_a_warm_group_is_not_announced(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(_kernel_cache, "CACHE_DIR", tmp_path)
    monkeypatch.setattr(_kernel_cache, "_announced", False)
    _kernel_cache.mark_warm("done")
    with _kernel_cache.compiling("done", "nothing"):
        pass
    assert capsys.readouterr().err == "" and not _kernel_cache._announced


def test_an_empty_cache_is_announced_before_any_kernel_and_a_filled_one_is_not(
        tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(_kernel_cache, "CACHE_DIR", tmp_path)
    monkeypatch.setattr(_kernel_cache, "_announced", False)
    (tmp_path / "tour_x").mkdir()
    (tmp_path / "tour_x" / "solve.f-1.py311.nbi").write_bytes(b"")  # one compiled kernel
    _kernel_cache.announce_if_empty("the kernels")
    assert capsys.readouterr().err == "" and not _kernel_cache._announced
    (tmp_path / "tour_x" / "solve.f-1.py311.nbi").unlink()
    _kernel_cache.announce_if_empty("the kernels this batch needs")
    said = capsys.readouterr().err
    assert said.count("\n") == 1 and "compiling the kernels this batch needs" in said
    _kernel_cache.announce_if_empty("the kernels this batch needs")  # once per process
    assert capsys.readouterr().err == ""


_FIRST_KERNEL = """
import numba, numpy as np
from numba.core import event
from subtask_opt.kinematics import _kernels as k
from subtask_opt.kinematics.planar import load_planar_arm

levels = {}
class Levels(event.Listener):  # registered after the package's own listener
    def on_start(self, ev):
        levels[ev.data["dispatcher"].py_func.__name__] = int(numba.config.OPT)
    def on_end(self, ev):
        pass
event.register("numba:compile", Levels())

@numba.njit
def users_own(x):
    return x + 1

arm = load_planar_arm("planar_2r")
k.fk_batch(arm.kinematics, np.zeros((1, 2)))
users_own(1)
print(levels.get("fk_batch"), levels.get("users_own"), int(numba.config.OPT))
"""


@pytest.mark.skipif(REDUCED, reason="NUMBA_DISABLE_JIT: nothing is compiled")
def test_the_first_compiled_kernel_is_announced_and_built_at_the_package_level(tmp_path):
    env = dict(os.environ, SUBTASK_OPT_CACHE_DIR=str(tmp_path))
    runs = [subprocess.run([sys.executable, "-c", _FIRST_KERNEL], env=env, capture_output=True,
                           text=True, timeout=300, cwd=PROJECT_ROOT) for _ in range(2)]
    assert [r.returncode for r in runs] == [0, 0], runs[0].stderr
    cold, warm = (r.stderr for r in runs)
    assert cold.count("\n") == 1 and "compiling the kernels this run needs (numba" in cold
    assert warm == ""
    # the package's kernel at its own level, the user's and numba's setting at numba's
    default = str(int(numba.config.OPT))
    assert runs[0].stdout.split() == [str(_kernel_cache.KERNEL_OPT), default, default]


class _Dispatcher:
    def __init__(self, module: str) -> None:
        self.py_func = type("F", (), {"__module__": module})()


def test_the_package_level_holds_only_while_its_own_kernels_compile(monkeypatch) -> None:
    from numba.core import event

    monkeypatch.setattr(numba.config, "OPT", type(numba.config.OPT)(3))
    listener = _kernel_cache._PackageCompiles()

    def start(module: str) -> None:
        listener.on_start(event.Event("numba:compile", event.EventStatus.START,
                                      data={"dispatcher": _Dispatcher(module)}))

    def end() -> None:
        listener.on_end(event.Event("numba:compile", event.EventStatus.END))

    start("users.code")
    assert numba.config.OPT == 3
    start("subtask_opt.ga.loop")  # one of ours, called from the user's kernel
    assert numba.config.OPT == _kernel_cache.KERNEL_OPT
    start("numba.np.arrayobj")  # numba's own helpers inside ours follow ours
    assert numba.config.OPT == _kernel_cache.KERNEL_OPT
    end()
    end()
    assert numba.config.OPT == 3
    end()
    assert numba.config.OPT == 3 and numba.config.OPT.is_opt_max is False


_LOAD = """
import sys
from numba.core import event
from subtask_opt import _kernel_cache
sys.path.insert(0, sys.argv[1])
import cached_kernel  # defines a cache=True kernel

compiles = []
class Compiles(event.Listener):
    def on_start(self, ev):
        compiles.append(ev.data["dispatcher"].py_func.__name__)
    def on_end(self, ev):
        pass
event.register("numba:compile", Compiles())
with _kernel_cache.compile_seconds() as spent:
    cached_kernel.f(1.0)
print(len(compiles), spent[0] > 0.0)
"""


@pytest.mark.skipif(REDUCED, reason="NUMBA_DISABLE_JIT: nothing is compiled or loaded")
def test_compile_seconds_counts_a_kernel_loaded_from_the_cache(tmp_path):
    (tmp_path / "cached_kernel.py").write_text(
        "from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return x * 2.0\n")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               SUBTASK_OPT_CACHE_DIR=str(tmp_path / "ours"))
    runs = [subprocess.run([sys.executable, "-c", _LOAD, str(tmp_path)], env=env,
                           capture_output=True, text=True, timeout=300, cwd=PROJECT_ROOT)
            for _ in range(2)]
    assert [r.returncode for r in runs] == [0, 0], runs[0].stderr
    # compiled in the first process, loaded from the cache in the second: counted both times
    assert [r.stdout.split() for r in runs] == [["1", "True"], ["0", "True"]]


def test_compile_seconds_counts_compilation_only() -> None:
    from numba import njit

    @njit  # not cached: compiled inside the block
    def twice(x):
        return 2 * x

    with _kernel_cache.compile_seconds() as compiled:
        assert twice(3) == 6
    assert compiled[0] > 0.0
    with _kernel_cache.compile_seconds() as again:
        assert twice(4) == 8  # already compiled
    assert again == [0.0]


_WAITER = """
import sys
from pathlib import Path
from subtask_opt import _kernel_cache
_kernel_cache.CACHE_DIR = Path(sys.argv[1])
(Path(sys.argv[1]) / "started").touch()
with _kernel_cache.compiling("locked", "the locked kernels"):
    (Path(sys.argv[1]) / "entered").touch()
"""


@pytest.mark.skipif(sys.platform == "win32", reason="fcntl locks")
def test_a_second_process_waits_for_the_group_being_compiled_and_then_loads_it(
        tmp_path, monkeypatch):
    import time

    monkeypatch.setattr(_kernel_cache, "CACHE_DIR", tmp_path)
    env = dict(os.environ, PYTHONPATH=str(PROJECT_ROOT))
    with _kernel_cache._group_lock("locked"):  # this process is "compiling" the group
        child = subprocess.Popen([sys.executable, "-c", _WAITER, str(tmp_path)], env=env,
                                 stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 120
        while not (tmp_path / "started").exists() and child.poll() is None:
            assert time.monotonic() < deadline, "the child never started"
            time.sleep(0.05)
        time.sleep(0.5)
        assert not (tmp_path / "entered").exists()  # it waits while the group compiles
        _kernel_cache.mark_warm("locked")
    _, err = child.communicate(timeout=120)
    assert child.returncode == 0, err
    assert (tmp_path / "entered").exists()
    assert "compiling" not in err  # it found the group warm: nothing announced


@pytest.mark.skipif(sys.platform == "win32", reason="fcntl locks")
def test_a_held_lock_is_waited_for_at_most_the_lock_wait(tmp_path, monkeypatch):
    import fcntl

    monkeypatch.setattr(_kernel_cache, "CACHE_DIR", tmp_path)
    monkeypatch.setattr(_kernel_cache, "LOCK_WAIT_S", 0.3)
    with open(tmp_path / "stuck.lock", "a") as holder:  # a holder that never lets go
        fcntl.flock(holder, fcntl.LOCK_EX)
        entered = []
        with _kernel_cache._group_lock("stuck"):
            entered.append(True)
    assert entered == [True]
