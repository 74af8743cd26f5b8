"""No code execution or unpickling of input anywhere in the package: its syntax trees (not a
text grep, so JavaScript in a string or ``re.compile`` cannot trip it) hold no call of
``eval``/``exec``/``compile``/``__import__``, no use of ``pickle``-like loaders, no
``allow_pickle=True`` and no shell, except the exceptions listed here with their reason."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "subtask_opt"

BUILTINS = {"eval", "exec", "compile", "__import__", "execfile"}
"""Builtins that run or build code from a string."""

LOADER_MODULES = {"pickle", "_pickle", "cPickle", "dill", "cloudpickle", "marshal", "shelve",
                  "jsonpickle", "joblib"}
"""Modules whose loaders run code chosen by the data."""

UNSAFE_ATTRIBUTES = {("os", "system"), ("os", "popen"), ("builtins", "eval"),
                     ("builtins", "exec"), ("builtins", "compile"), ("pandas", "read_pickle"),
                     ("yaml", "load"), ("yaml", "unsafe_load"), ("yaml", "full_load")}

ALLOWED = {
    # A PlanarProblem/MatrixProblem handed to solve_many() in memory travels to the worker
    # processes as bytes made by _pickle_problem() from that object; no file, argument or
    # network input is ever unpickled (checked by test_the_pickle_exception_is_only_our_bytes).
    ("batch/jobs.py", "import pickle"),
    ("batch/jobs.py", "pickle.dumps"),
    ("batch/jobs.py", "pickle.loads"),
    # map_jobs(isolate=True): a job's outcome comes back from the process forked for it
    # through an anonymous pipe this process created (os.pipe before os.fork): the bytes are
    # our own child's, as multiprocessing's own result pickles are (checked by
    # test_the_pool_unpickles_only_its_childs_pipe).
    ("batch/pool.py", "import pickle"),
    ("batch/pool.py", "pickle.dumps"),
    ("batch/pool.py", "pickle.loads"),
}


def findings(source: str) -> list[tuple[int, str]]:
    """(line, what) for every unsafe construct in ``source``."""
    tree = ast.parse(source)
    aliases: dict[str, str] = {}  # local name -> module (import pickle as p)
    imported: dict[str, str] = {}  # local name -> module.attr (from pickle import loads)
    found: list[tuple[int, str]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                root = a.name.split(".")[0]
                aliases[a.asname or root] = a.name
                if root in LOADER_MODULES:
                    found.append((node.lineno, f"import {a.name}"))
        elif isinstance(node, ast.ImportFrom) and node.module:
            root = node.module.split(".")[0]
            for a in node.names:
                imported[a.asname or a.name] = f"{node.module}.{a.name}"
                if root in LOADER_MODULES or (root, a.name) in UNSAFE_ATTRIBUTES or (
                        root == "builtins" and a.name in BUILTINS):
                    found.append((node.lineno, f"from {node.module} import {a.name}"))
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        func = node.func
        if isinstance(func, ast.Name):
            if func.id in BUILTINS:
                found.append((node.lineno, f"{func.id}()"))
            target = imported.get(func.id, "")
            if target.split(".")[0] in LOADER_MODULES:
                found.append((node.lineno, target))
        elif isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name):
            module = aliases.get(func.value.id, "")
            root = module.split(".")[0]
            if root in LOADER_MODULES:
                found.append((node.lineno, f"{root}.{func.attr}"))
            elif (root, func.attr) in UNSAFE_ATTRIBUTES:
                found.append((node.lineno, f"{root}.{func.attr}"))
        for kw in node.keywords:
            if kw.arg in {"allow_pickle", "shell"} and not (
                    isinstance(kw.value, ast.Constant) and kw.value.value is False):
                found.append((node.lineno, f"{kw.arg}={ast.unparse(kw.value)}"))
    return sorted(found)


def _package_findings() -> dict[tuple[str, str], list[int]]:
    out: dict[tuple[str, str], list[int]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        for line, what in findings(path.read_text(encoding="utf-8")):
            out.setdefault((rel, what), []).append(line)
    return out


def test_no_eval_exec_or_unpickling_in_the_package() -> None:
    files = list(PACKAGE.rglob("*.py"))
    assert len(files) > 50  # the scan sees the package
    unexpected = {k: v for k, v in _package_findings().items() if k not in ALLOWED}
    assert unexpected == {}, "code execution or unpickling: " + "; ".join(
        f"{f}:{lines} {what}" for (f, what), lines in sorted(unexpected.items()))


def test_every_listed_exception_still_exists() -> None:
    """A stale entry would silently allow the construct back later."""
    assert set(_package_findings()) >= ALLOWED


def test_the_pickle_exception_is_only_our_bytes() -> None:
    """``pickle.loads`` in batch/jobs.py reads ``_Task.problem`` only, and every ``_Task`` built
    with a problem gets it from ``_pickle_problem(...)`` (an in-memory object we pickled)."""
    tree = ast.parse((PACKAGE / "batch" / "jobs.py").read_text(encoding="utf-8"))
    loads = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
             and ast.unparse(n.func) == "pickle.loads"]
    assert [ast.unparse(n.args[0]) for n in loads] == ["task.problem"]
    calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
             and ast.unparse(n.func) in {"_Task", "replace", "dataclasses.replace"}]
    problems = [kw.value for n in calls for kw in n.keywords if kw.arg == "problem"]
    assert problems and all(isinstance(v, ast.Call) and ast.unparse(v.func) == "_pickle_problem"
                            for v in problems)
    assert not [n for n in calls if ast.unparse(n.func) == "_Task" and len(n.args) > 4]
    assert not [t for n in ast.walk(tree) if isinstance(n, (ast.Assign, ast.AnnAssign))
                for t in (n.targets if isinstance(n, ast.Assign) else [n.target])
                if isinstance(t, ast.Attribute) and t.attr == "problem"]


def test_the_pool_unpickles_only_its_childs_pipe() -> None:
    """``pickle.loads`` in batch/pool.py reads only what ``os.read`` returned from the read
    end of the pipe made right before ``os.fork`` in the same function."""
    tree = ast.parse((PACKAGE / "batch" / "pool.py").read_text(encoding="utf-8"))
    loads = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
             and ast.unparse(n.func) == "pickle.loads"]
    assert [ast.unparse(n.args[0]) for n in loads] == ["b''.join(chunks)"]
    fn = next(n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)
              and n.name == "_run_forked")
    text = ast.unparse(fn)
    assert text.index("os.pipe()") < text.index("os.fork()") < text.index("pickle.loads")
    appends = [n for n in ast.walk(fn) if isinstance(n, ast.Call)
               and ast.unparse(n.func) == "chunks.append"]
    assert [ast.unparse(n.args[0]) for n in appends] == ["block"]
    assert "block = os.read(read_fd, 1 << 20)" in text


@pytest.mark.parametrize("snippet,what", [
    ("eval(text)", "eval()"),
    ("x = exec(code, {})", "exec()"),
    ("compile(src, 'f', 'exec')", "compile()"),
    ("__import__(name)", "__import__()"),
    ("import pickle\npickle.loads(data)", "pickle.loads"),
    ("import pickle as p\np.load(fh)", "pickle.load"),
    ("from pickle import loads as l\nl(data)", "pickle.loads"),
    ("import cloudpickle\ncloudpickle.loads(b)", "cloudpickle.loads"),
    ("import marshal\nmarshal.loads(b)", "marshal.loads"),
    ("import numpy as np\nnp.load(f, allow_pickle=True)", "allow_pickle=True"),
    ("import numpy as np\nnp.load(f, allow_pickle=flag)", "allow_pickle=flag"),
    ("import subprocess\nsubprocess.run(cmd, shell=True)", "shell=True"),
    ("import os\nos.system(cmd)", "os.system"),
    ("import builtins\nbuiltins.eval(s)", "builtins.eval"),
    ("import yaml\nyaml.load(fh)", "yaml.load"),
    ("import pandas as pd\npd.read_pickle(p)", "pandas.read_pickle"),
])
def test_the_scan_finds_each_construct(snippet: str, what: str) -> None:
    assert what in [w for _, w in findings(snippet)]


@pytest.mark.parametrize("snippet", [
    "import re\nre.compile(r'x')",
    "page = 'var m = /x/.exec(window.location.hash); eval(1)'",
    "model.eval()",
    "np.load(f, allow_pickle=False)",
    "subprocess.run(cmd, shell=False)",
    "import numpy as np\nnp.load(f)",
    "import json\njson.loads(text)",
    "def evaluate(x):\n    return x\nevaluate(1)",
])
def test_the_scan_passes_safe_code(snippet: str) -> None:
    assert findings(snippet) == []
