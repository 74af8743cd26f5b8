"""The kernel cache folder follows the kernel sources: any edit selects a fresh folder."""

from __future__ import annotations

from pathlib import Path

import pytest

from subtask_opt import _kernel_cache


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
