"""Today's tree against an older commit, in one run: a ratio per workload, exit 1 on a regression.

The older commit (``--against``, default ``5647307``, v0.1) is checked out once into a
git worktree of its own (``--worktree``, default ``~/.cache/subtask_opt-regress/<sha>``,
outside the kernel cache that ``make clean`` removes)
and imported from there; today's tree is the one this script sits in, uncommitted edits
included. Each workload runs in fresh worker processes (this file with ``--worker``, the
tree on ``PYTHONPATH``), the trees alternating (old, new, then new, old, ...) for
``--rounds`` rounds; each worker loads or compiles its kernels on a small instance first,
so no figure holds compilation. Printed per workload: the median of each tree's figure,
and the ratio today / older (above 1 is slower, or for a tour length longer).

Workloads (``--only`` picks some):

* ``trap30``: ``runtime_s`` of ``solve`` on the built-in ``random30`` sets 0-9 of
  planar_2r, trapezoid model, fixed elbows, seeds 0-4, stopped after 15 generations
  without improvement (both trees' default stall at 30 nodes) and without today's
  lower-bound target, so that every solve runs its stall: the cost of the search per
  generation. The median over the 50 solves; ``trap30_cpu`` is the same median with the
  loop's clock read as process CPU time (less noisy on a shared machine).
* ``tsp400``, ``tsp1600``, ``tsp3200``: CPU of ``MatrixProblem`` (v0.1:
  ``SequencingProblem.from_matrix``) plus ``solve`` at the default stop, on N uniform
  random points (the instance of ``benchmarks/growth.py``, seed 1000 N), solve seed 0;
  ``tsp*_len`` is the tour length over sqrt(N) (lower is better; 0.7124 is the
  asymptotic optimum). From their CPU the growth exponent b of time = a N^b between 400
  and 3200, per tree.
* ``line100``, ``line300``: CPU of ``travel_times(subtasks, arm, "line")`` on planar_2r
  (joint jerk limits: today's lines are jerk-limited) and ``random_subtasks(arm, N,
  seed=0)``; ``line*_mean`` is the mean finite line time.
* ``robotsp245``: search CPU of our solver on RoboTSP's 245 holes (``cpu['search']`` of
  :func:`~subtask_opt.arm.serial_problem.solve_serial_problem`, compilation apart; the data in
  ``--data``); a tree without serial arms says so and has no ratio.

A ratio above :data:`LIMIT` fails the run (exit 1) unless :data:`REASONS` states why for
that workload and older commit (up to the ratio the reason covers), and so does today's
growth exponent above :data:`GROWTH_LIMIT`; a ratio no tree could produce (a workload
missing in the older tree) is shown as ``n/a``. ``--json PATH`` also writes the whole
result as JSON (``--json`` alone prints it instead of the table). Bad arguments: one line
on stderr, exit 2.

    python benchmarks/regress.py [--against 5647307] [--rounds 3] [--only trap30,tsp3200]
        [--data ../shared/data] [--worktree DIR] [--json [PATH]]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time
import types
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
LIMIT = 1.10
"""A ratio (today / older) above this is a regression unless :data:`REASONS` explains it."""
DEFAULT_AGAINST = "5647307"
WORKLOADS = ("trap30", "tsp400", "tsp1600", "tsp3200", "line100", "line300", "robotsp245")

GROWTH_LIMIT = 1.6
"""Today's growth exponent (TSP CPU ~ N^b from 400 to 3200) above this fails the run."""

REASONS: dict[str, dict[str, tuple[float, str]]] = {
    "5647307": {
        "tsp400": (4.0, "quality: today's default polishes with 3-opt moves, 40 kicks per "
                        "child and alpha-nearness lists; its tours are 1.2% shorter than "
                        "v0.1's (length/sqrt(N) 0.732 vs 0.741) and TSPLIB up to a280 is "
                        "solved to the optimum (benchmarks/tsplib.py)"),
        "tsp1600": (2.5, "quality: 100 kicks per child and 40 generations; tours 2.3% "
                         "shorter than v0.1's (0.729 vs 0.746; 20 generations: 1.4 s CPU "
                         "for 0.7292, 40: 2.0 s for 0.7288)"),
        "line100": (1.5, "jerk limits: v0.1 timed lines acceleration-limited only; today's "
                         "lines are the jerk-limited profiles the arm executes (a width "
                         "search and an exact check per line on top of the same TOPP); "
                         "issue 31 accepts up to 1.5x"),
        "line300": (1.5, "jerk limits, as line100"),
    },
}
"""Why a ratio above :data:`LIMIT` is accepted, by older commit (as given or its short sha)
and workload, with the highest ratio the reason covers: a workload without an entry, or
above its ceiling, fails the run."""


class _OneLineParser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        print(f"regress.py: error: {message}", file=sys.stderr)
        sys.exit(2)


def _bad(message: str) -> None:
    print(f"regress.py: error: {message}", file=sys.stderr)
    sys.exit(2)


# --- workers: run inside one tree (old or new API), print one JSON line -------------


def _clock_is_cpu() -> None:
    """The GA loop's clock read as process CPU time (``runtime_s`` becomes search CPU)."""
    for name in ("subtask_opt.ga.loop", "subtask_opt.ga.core"):
        try:
            module = __import__(name, fromlist=["time"])
        except ImportError:
            continue
        module.time = types.SimpleNamespace(perf_counter=time.process_time)  # type: ignore[attr-defined]


class _Api:
    """The names of the tree this worker imports: today's (``load_robot``, ``ArmProblem``,
    ``MatrixProblem``, ``solve_serial_problem``) or v0.1's (``load_arm``,
    ``SequencingProblem``, ``from_matrix``, ``solve_serial``)."""

    def __init__(self) -> None:
        import subtask_opt as so

        self.so: Any = so
        self.today = hasattr(so, "ArmProblem")

    def planar_arm(self, name: str) -> Any:
        """(the object ``builtin_case`` and ``travel_times`` take, the robot a problem takes)"""
        if self.today:
            robot = self.so.load_robot(name)  # (the attributes differ by tree: Any)
            return robot.model, robot
        arm = self.so.load_arm(name)
        return arm, arm

    def planar_problem(self, subtasks: Any, robot: Any, **options: Any) -> Any:
        if self.today:
            return self.so.ArmProblem(subtasks, robot, **options)
        return self.so.SequencingProblem(subtasks, robot, **options)

    def matrix_problem(self, m: Any) -> Any:
        if self.today:
            return self.so.MatrixProblem(m)
        return self.so.SequencingProblem.from_matrix(m)

    def random_subtasks(self) -> Any:
        try:
            from subtask_opt.arm.tasks import random_subtasks
        except ImportError:  # v0.1's layout
            from subtask_opt.tasks import random_subtasks  # type: ignore[no-redef]
        return random_subtasks

    def travel_times(self) -> Any:
        try:
            from subtask_opt.arm.timing.models import travel_times
        except ImportError:  # v0.1's layout
            from subtask_opt.timing import travel_times  # type: ignore[no-redef]
        return travel_times


@contextmanager
def _timed() -> Iterator[dict[str, float]]:
    """CPU seconds of the block into ``["cpu"]``, numba's compiling or loading of kernels
    inside it apart into ``["compile"]`` (0 in a tree without
    ``subtask_opt._kernel_cache.compile_seconds``: v0.1 times only after its warm-up)."""
    out = {"cpu": 0.0, "compile": 0.0}
    try:
        from subtask_opt._kernel_cache import compile_seconds
    except ImportError:
        compile_seconds = None  # type: ignore[assignment]
    t0 = time.process_time()
    if compile_seconds is None:
        yield out
    else:
        with compile_seconds() as spent:
            yield out
        out["compile"] = spent[0]
    out["cpu"] = time.process_time() - t0 - out["compile"]


def _uniform(n: int, seed: int):  # noqa: ANN202
    import numpy as np

    pts = np.random.default_rng(seed).random((n, 2))
    return np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))


def _trap30(cpu_clock: bool) -> dict[str, Any]:
    api = _Api()
    so = api.so
    if cpu_clock:
        _clock_is_cpu()
    arm, robot = api.planar_arm("planar_2r")
    problems = [api.planar_problem(so.builtin_case("random30", arm, seed=g), robot,
                                   time_model="trapezoid", configurations="fixed")
                for g in range(10)]
    stop = [so.NoImprovement(15), so.MaxGenerations(50_000)]
    so.solve(problems[0], seed=0, stop=stop)  # kernels loaded (or compiled) first
    times, generations, total = [], 0, 0.0
    for problem in problems:
        for seed in range(5):
            result = so.solve(problem, seed=seed, stop=stop)
            times.append(result.runtime_s)
            generations += result.generations
            total += result.total_time
    return {"value": statistics.median(times), "generations": generations,
            "total_time": total}


def _tsp(n: int) -> dict[str, Any]:
    api = _Api()
    api.so.solve(api.matrix_problem(_uniform(150, 1)), seed=0)  # kernels, candidates
    m = _uniform(n, 1000 * n)
    with _timed() as spent:
        result = api.so.solve(api.matrix_problem(m), seed=0)
    return {"value": spent["cpu"], "compile": spent["compile"],
            "len": result.total_time / math.sqrt(n), "generations": result.generations}


def _line(n: int) -> dict[str, Any]:
    import numpy as np

    api = _Api()
    random_subtasks, travel_times = api.random_subtasks(), api.travel_times()
    arm, _ = api.planar_arm("planar_2r")
    travel_times(random_subtasks(arm, 4, seed=1), arm, "line")  # kernels
    subtasks = random_subtasks(arm, n, seed=0)
    with _timed() as spent:
        timing = travel_times(subtasks, arm, "line")
    m = np.asarray(timing.matrix)
    return {"value": spent["cpu"], "compile": spent["compile"],
            "mean": float(m[np.isfinite(m) & (m > 0)].mean())}


def _robotsp(data: Path) -> dict[str, Any]:
    import numpy as np

    try:
        from subtask_opt.arm.poses import make_targets
        from subtask_opt.arm.serial_problem import SerialProblem
        from subtask_opt.cell.scene import Scene
        from subtask_opt.kinematics.ik import IKParams
        from subtask_opt.kinematics.serial import load_serial_arm
    except ImportError as exc:
        return {"unavailable": f"no serial arms in this tree ({exc.name})"}
    try:
        from subtask_opt.papers.robotsp import HOME_DEG, _load
    except ImportError:  # before RoboTSP's benchmark moved to papers/
        from subtask_opt.arm.robotsp_bench import (  # type: ignore[no-redef]
            HOME_DEG,
            _load,
        )
    try:
        from subtask_opt.arm.serial_problem import solve_serial_problem as solve_serial
    except ImportError:  # before the #26 refactor
        from subtask_opt.arm.serial_problem import (  # type: ignore[attr-defined,no-redef]
            solve_serial,
        )
    folder = data / "robotsp"
    rows, subsets, _ = _load(folder)
    arm = load_serial_arm("vs060_drill", limits="robotsp")
    scene = Scene.load(folder / "obstacles.json")
    home = np.radians(HOME_DEG)

    def problem(size: str) -> Any:
        targets = make_targets(rows[subsets[size]], axis_step=45.0, standoff=0.01)
        return SerialProblem(targets, arm, home, scene=scene,
                             ik=IKParams(wrap_alternatives=int(size) <= 100))

    solve_serial(problem("25"), seed=0)  # kernels loaded (or compiled) first
    result = solve_serial(problem("245"), seed=0)
    cpu = getattr(result, "cpu", None) or result.report.cpu
    return {"value": cpu["search"], "compile": cpu.get("compile", 0.0),
            "executed_time": result.total_time}


def worker(name: str, data: Path) -> dict[str, Any]:
    """One workload in this process's tree."""
    if name in ("trap30", "trap30_cpu"):
        return _trap30(name == "trap30_cpu")
    if name.startswith("tsp"):
        return _tsp(int(name[3:]))
    if name.startswith("line"):
        return _line(int(name[4:]))
    if name == "robotsp245":
        return _robotsp(data)
    raise ValueError(name)


# --- driver ------------------------------------------------------------------------


def _git(*args: str) -> str:
    return subprocess.run(["git", "-C", str(ROOT), *args], check=True, capture_output=True,
                          text=True).stdout.strip()


def _resolve(commit: str) -> str:
    try:
        return _git("rev-parse", "--verify", "--quiet", f"{commit}^{{commit}}")
    except subprocess.CalledProcessError:
        _bad(f"--against {commit!r} is not a commit of {ROOT}")
    raise AssertionError  # unreachable


def _worktree(sha: str, folder: Path | None) -> Path:
    """A checkout of ``sha`` (created once, reused while its HEAD is ``sha``)."""
    if folder is None:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
        folder = base / "subtask_opt-regress" / sha[:12]
    if (folder / ".git").exists():
        head = subprocess.run(["git", "-C", str(folder), "rev-parse", "HEAD"],
                              capture_output=True, text=True).stdout.strip()
        if head == sha:
            return folder
        _bad(f"--worktree {folder} holds {head[:12] or 'something else'}, not {sha[:12]}")
    if folder.exists() and any(folder.iterdir()):
        _bad(f"--worktree {folder} exists and is not a checkout of {sha[:12]}")
    folder.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(folder), sha],
                   check=True, capture_output=True, text=True)
    return folder


def _run_worker(tree: Path, name: str, data: Path) -> dict[str, Any]:
    env = dict(os.environ, PYTHONPATH=str(tree))
    done = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--worker", name,
                           "--data", str(data)], env=env, capture_output=True, text=True,
                          cwd=tree)
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    if done.returncode != 0 or not lines:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        return {"error": f"worker {name} failed in {tree}: {tail}"}
    return json.loads(lines[-1])


def _median(runs: list[dict[str, Any]], key: str) -> float | None:
    values = [r[key] for r in runs if key in r]
    return statistics.median(values) if values else None


def measure(old: Path, new: Path, names: list[str], rounds: int, data: Path,
            log: Any) -> dict[str, dict[str, Any]]:
    """Every workload in both trees, alternating, ``rounds`` times."""
    results: dict[str, dict[str, Any]] = {}
    for name in names:
        runs: dict[str, list[dict[str, Any]]] = {"old": [], "new": []}
        for r in range(rounds):
            order = ("old", "new") if r % 2 == 0 else ("new", "old")
            for which in order:
                runs[which].append(_run_worker(old if which == "old" else new, name, data))
                print(f"  {name} round {r + 1}/{rounds} {which}: "
                      f"{json.dumps(runs[which][-1])}", file=log, flush=True)
        results[name] = runs
    return results


def summarise(results: dict[str, dict[str, Any]], against: str,
              sha: str) -> dict[str, Any]:
    reasons = {**REASONS.get(sha[:7], {}), **REASONS.get(against, {})}
    rows: dict[str, Any] = {}

    def row(name: str, key: str, runs: dict[str, list[dict[str, Any]]],
            reason_key: str) -> None:
        old, new = _median(runs["old"], key), _median(runs["new"], key)
        problem = next((r.get("unavailable") or r.get("error") for side in ("old", "new")
                        for r in runs[side] if "unavailable" in r or "error" in r), None)
        ratio = new / old if old and new is not None and old > 0 else None
        ceiling, why = reasons.get(reason_key, (LIMIT, None))
        reason = None
        if ratio is not None and ratio > LIMIT and why is not None:
            reason = why if ratio <= ceiling else None
        rows[name] = {"old": old, "new": new, "ratio": ratio, "note": problem,
                      "reason": reason, "ceiling": ceiling if why else LIMIT}

    for name, runs in results.items():
        row(name, "value", runs, name)
        if name.startswith("trap30"):
            for which in ("old", "new"):
                rows[name][f"{which}_generations"] = _median(runs[which], "generations")
        if name.startswith("tsp"):
            row(f"{name}_len", "len", runs, f"{name}_len")
        if name.startswith("line"):
            rows[name]["old_mean"] = _median(runs["old"], "mean")
            rows[name]["new_mean"] = _median(runs["new"], "mean")
    growth: dict[str, float | None] = {}
    if "tsp400" in rows and "tsp3200" in rows:
        for which in ("old", "new"):
            a, b = rows["tsp400"][which], rows["tsp3200"][which]
            growth[which] = math.log(b / a) / math.log(8) if a and b else None
    failed = [n for n, r in rows.items() if r["ratio"] is not None and r["ratio"] > LIMIT
              and not r["reason"]]
    b_new = growth.get("new")
    if b_new is not None and b_new > GROWTH_LIMIT:
        failed.append("growth_exponent")
    errors = [n for n, r in rows.items() if r["note"] and r["note"].startswith("worker")]
    return {"against": against, "against_sha": sha, "tree": str(ROOT),
            "tree_head": _git("rev-parse", "HEAD"),
            "tree_dirty": bool(_git("status", "--porcelain", "--untracked-files=no")),
            "limit": LIMIT, "workloads": rows, "growth_exponent_400_3200": growth,
            "load_average": os.getloadavg()[0], "cpus": os.cpu_count(),
            "regressions": failed, "errors": errors,
            "status": "ok" if not failed and not errors else "regression"}


def table(summary: dict[str, Any]) -> str:
    lines = [f"today's tree {summary['tree_head'][:10]}"
             f"{' (edited)' if summary['tree_dirty'] else ''} against "
             f"{summary['against']} ({summary['against_sha'][:10]}); load average "
             f"{summary['load_average']:.1f} on {summary['cpus']} CPUs",
             f"{'workload':<14} {'older':>10} {'today':>10} {'ratio':>7}  note"]
    for name, r in summary["workloads"].items():
        seconds = not name.endswith("_len")

        def fmt(v: float | None, seconds: bool = seconds) -> str:
            if v is None:
                return "-"
            if not seconds:
                return f"{v:.5f}"
            return f"{v * 1e3:.2f} ms" if v < 1.0 else f"{v:.3f} s"

        ratio = "n/a" if r["ratio"] is None else f"{r['ratio']:.2f}x"
        note = r["note"] or ""
        if r["ratio"] is not None and r["ratio"] > LIMIT:
            note = (f"accepted up to {r['ceiling']:.2f}x: " + r["reason"]) if r["reason"] else (
                "REGRESSION" + (f" (above the {r['ceiling']:.2f}x a reason covers)"
                                if r["ceiling"] > LIMIT else " (no reason)"))
        if name.startswith("line") and r.get("old_mean") is not None:
            note = (f"mean line {r['old_mean']:.4f} -> {r['new_mean']:.4f} s; " + note).strip()
        lines.append(f"{name:<14} {fmt(r['old']):>10} {fmt(r['new']):>10} {ratio:>7}  {note}")
    g = summary["growth_exponent_400_3200"]
    if g:
        lines.append("growth exponent (TSP CPU ~ N^b, 400 -> 3200): "
                     + ", ".join(f"{k} b = {v:.2f}" for k, v in g.items() if v is not None))
    lines.append(f"status: {summary['status']}"
                 + (f" ({', '.join(summary['regressions'] + summary['errors'])})"
                    if summary['status'] != "ok" else ""))
    return "\n".join(lines)


def main() -> int:
    ap = _OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", default=DEFAULT_AGAINST, help="the older commit")
    ap.add_argument("--rounds", type=int, default=3, help="alternating rounds (>= 1)")
    ap.add_argument("--only", default=",".join(WORKLOADS),
                    help=f"comma-separated workloads of {', '.join(WORKLOADS)}")
    ap.add_argument("--data", type=Path, default=DATA, help="the shared data folder")
    ap.add_argument("--worktree", type=Path, default=None,
                    help="where the older commit is checked out")
    ap.add_argument("--json", nargs="?", const="-", default=None, metavar="PATH",
                    help="write the result as JSON to PATH (the table still printed); "
                         "without PATH print JSON instead of the table")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker is not None:
        print(json.dumps(worker(args.worker, args.data)))
        return 0
    if args.rounds < 1 or args.rounds > 100:
        _bad(f"--rounds must be in [1, 100], got {args.rounds}")
    names = [n.strip() for n in args.only.split(",") if n.strip()]
    unknown = [n for n in names if n not in WORKLOADS + ("trap30_cpu",)]
    if not names or unknown:
        _bad(f"--only: unknown workload {unknown[0] if unknown else '(none)'!r}; "
             f"choose from {', '.join(WORKLOADS)}, trap30_cpu")
    if "trap30" in names and "trap30_cpu" not in names:
        names.insert(names.index("trap30") + 1, "trap30_cpu")
    if "robotsp245" in names and not (args.data / "robotsp" / "targets.csv").is_file():
        _bad(f"--data {args.data}: no robotsp/targets.csv (leave robotsp245 out with --only)")
    sha = _resolve(args.against)
    old = _worktree(sha, args.worktree)
    log = sys.stderr
    print(f"regress.py: {old} ({sha[:10]}) against {ROOT}, {args.rounds} rounds", file=log)
    results = measure(old, ROOT, names, args.rounds, args.data, log)
    summary = summarise(results, args.against, sha)
    if args.json not in (None, "-"):
        Path(args.json).write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps(summary, indent=1) if args.json == "-" else table(summary))
    return 0 if summary["status"] == "ok" else 1


if __name__ == "__main__":
    sys.exit(main())
