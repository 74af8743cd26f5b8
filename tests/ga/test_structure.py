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

PACKAGE = Path(subtask_opt.__file__).parent
GA_DIR = PACKAGE / "ga"
ABOVE_GA = ("subtask_opt.tour", "subtask_opt.chromosomes", "subtask_opt.kinematics",
            "subtask_opt.cell", "subtask_opt.arm",
            "subtask_opt.planners", "subtask_opt.plotting", "subtask_opt.cli",
            "subtask_opt.batch", "subtask_opt.papers")
LAYERS = {"base": 0, "_kernel_cache": 0, "ga": 1, "chromosomes": 2, "tour": 3,
          "kinematics": 4, "planners": 4, "cell": 5, "arm": 6, "plotting": 7, "batch": 8,
          "papers": 8, "cli": 9}
"""The package's layers: a module may import from its own layer or a lower one only
(``chromosomes`` is the composition root of the GA's kinds; it imports its kinds' modules
lazily, when a caller asks for one)."""


def test_every_kind_has_all_five_operators() -> None:
    from subtask_opt.chromosomes import SOURCES, use

    assert set(TAGS) == set(Kind) == set(SOURCES)
    for kind in Kind:
        ops = dispatch.registered(use(kind))
        assert ops is not None, kind
        for name in dispatch.OPERATOR_NAMES:
            assert callable(getattr(ops, name)), (kind, name)


def test_importing_a_kernel_module_registers_nothing() -> None:
    code = ("import subtask_opt.tour.permutation, subtask_opt.tour.precedence, "
            "subtask_opt.tour.clustered, subtask_opt.planners.grid._waypoint_kernels\n"
            "from subtask_opt.ga import dispatch\n"
            "from subtask_opt.ga.kinds import Kind\n"
            "print([k.name for k in Kind if dispatch.registered(k) is not None])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def _imports(path: Path) -> list[str]:
    """Every ``subtask_opt`` module ``path`` imports, at any depth of its code (lazy
    imports inside functions included; ``if TYPE_CHECKING`` blocks left out)."""
    tree = ast.parse(path.read_text())
    skipped: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skipped |= {id(n) for n in ast.walk(node)}
    names = []
    for node in ast.walk(tree):
        if id(node) in skipped:
            continue
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.append(node.module)
        elif isinstance(node, ast.Import):
            names += [a.name for a in node.names]
    return [n for n in names if n.startswith("subtask_opt.")]


def _layer(module: str) -> int | None:
    return LAYERS.get(module.split(".")[1])


def test_dependencies_point_one_way() -> None:
    wrong = []
    for path in PACKAGE.rglob("*.py"):
        own = path.relative_to(PACKAGE).parts[0].removesuffix(".py")
        if own not in LAYERS:
            continue
        for name in _imports(path):
            layer = _layer(name)
            if layer is not None and layer > LAYERS[own]:
                wrong.append(f"{path.relative_to(PACKAGE)} imports {name}")
    assert not wrong, "\n".join(sorted(set(wrong)))


def test_no_module_level_import_circle() -> None:
    """The graph of module-level imports between the package's modules has no cycle."""
    modules = {".".join(("subtask_opt", *p.relative_to(PACKAGE).with_suffix("").parts))
               .removesuffix(".__init__"): p for p in PACKAGE.rglob("*.py")}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text())
        targets = set()
        for node in tree.body:  # module level only: a lazy import cannot close a circle
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                for a in node.names:
                    full = f"{node.module}.{a.name}"
                    targets.add(full if full in modules else node.module)
            elif isinstance(node, ast.Import):
                targets |= {a.name for a in node.names}
        graph[name] = {t for t in targets if t in modules and t != name}
    state: dict[str, int] = {}

    def visit(node: str, trail: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                raise AssertionError("import circle: " + " -> ".join([*trail, node, nxt]))
            if nxt not in state:
                visit(nxt, [*trail, node])
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node, [])


def test_registering_an_incomplete_operator_set_is_refused() -> None:
    incomplete = dispatch.OperatorSet(len, len, len, None, len)
    with pytest.raises(ParameterError, match="mutate"):
        dispatch.register(Kind.PERMUTATION, incomplete)
    with pytest.raises(ParameterError, match="Kind"):
        dispatch.register(0, dispatch.registered(Kind.PERMUTATION))  # type: ignore[arg-type]


def test_nothing_under_ga_imports_a_tour_or_a_domain() -> None:
    for path in GA_DIR.glob("*.py"):
        for name in _imports(path):
            assert not name.startswith(ABOVE_GA), f"{path.name} imports {name}"


def test_importing_the_package_loads_no_planner() -> None:
    code = ("import subtask_opt, sys; "
            "print(sorted(m for m in sys.modules if m.startswith('subtask_opt.planners')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def test_the_cli_starts_without_the_robot_or_solver_modules_and_every_public_name_loads() -> None:
    # the command line can speak (its notice, --help) before Pinocchio and the solver load;
    # the public names resolve on first use, each to the object its module defines
    code = ("import sys, subtask_opt.cli; "
            "print(sorted(m for m in ('pinocchio', 'subtask_opt.tour.solve', "
            "'subtask_opt.arm.problem') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
    import importlib

    import subtask_opt

    assert set(subtask_opt.__all__) == set(subtask_opt._MODULE_OF) <= set(dir(subtask_opt))
    for name in subtask_opt.__all__:
        module = importlib.import_module(subtask_opt._MODULE_OF[name])
        assert getattr(subtask_opt, name) is getattr(module, name)
    with pytest.raises(AttributeError, match="no_such_name"):
        subtask_opt.no_such_name  # noqa: B018
