"""The GA core's shape: every kind complete, no domain imports, one compiled loop per kind."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import subtask_opt
from subtask_opt.base.errors import ParameterError
from subtask_opt.ga import dispatch
from subtask_opt.ga.kinds import TAGS, Kind

GA_DIR = Path(subtask_opt.__file__).parent / "ga"
DOMAINS = ("subtask_opt.arm", "subtask_opt.planners", "subtask_opt.plotting", "subtask_opt.cli")


def test_every_kind_has_all_five_operators() -> None:
    import subtask_opt.arm._configuration_kernels  # noqa: F401  (registers its kind)
    import subtask_opt.planners.grid._waypoint_kernels  # noqa: F401  (registers its kind)

    assert set(TAGS) == set(Kind)
    for kind in Kind:
        ops = dispatch.registered(kind)
        assert ops is not None, kind
        for name in dispatch.OPERATOR_NAMES:
            assert callable(getattr(ops, name)), (kind, name)


def test_registering_an_incomplete_operator_set_is_refused() -> None:
    incomplete = dispatch.OperatorSet(len, len, len, None, len)
    with pytest.raises(ParameterError, match="mutate"):
        dispatch.register(Kind.PERMUTATION, incomplete)
    with pytest.raises(ParameterError, match="Kind"):
        dispatch.register(0, dispatch.registered(Kind.PERMUTATION))  # type: ignore[arg-type]


def test_nothing_under_ga_imports_a_domain() -> None:
    for path in GA_DIR.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            for name in names:
                assert not name.startswith(DOMAINS), f"{path.name} imports {name}"


def test_importing_the_package_loads_no_planner() -> None:
    code = ("import subtask_opt, sys; "
            "print(sorted(m for m in sys.modules if m.startswith('subtask_opt.planners')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
