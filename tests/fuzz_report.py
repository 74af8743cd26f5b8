"""pytest plugin: count the generated inputs of a fuzz run and enforce its per-input time limit.

Active only when ``FUZZ_REPORT`` names a JSON file (``make fuzz`` sets it).
Every hypothesis test case is counted through hypothesis' observability
callback (with its run time); loop-style tests (random worlds) add theirs with
:func:`record`. Each process (each xdist worker) writes its counts, slowest
input and peak memory next to the report; the controlling process merges them
into the report and prints one line, e.g.::

    fuzz: 10234 generated inputs in 19 tests, slowest 3.2 s (limit 10 s), peak RSS 812 MiB

An input slower than ``FUZZ_TIME_LIMIT_S`` (default 10 s) fails the run; the
first input that reaches a numba kernel pays for loading it, and counts too.
"""

from __future__ import annotations

import json
import os
import resource
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

REPORT = os.environ.get("FUZZ_REPORT", "")
LIMIT_S = float(os.environ.get("FUZZ_TIME_LIMIT_S", "10"))

_counts: Counter[str] = Counter()
_slowest: dict[str, float] = {}
_slowest_input: dict[str, str] = {}


def record(test: str, n: int = 1, seconds: float = 0.0, what: str = "") -> None:
    """Count ``n`` generated inputs of ``test``; ``seconds`` is the slowest one's time,
    ``what`` describes it (kept for the slowest input of each test)."""
    _counts[test] += n
    if seconds >= _slowest.get(test, 0.0):
        _slowest[test] = seconds
        _slowest_input[test] = what[:300]


class Timer:
    """Context manager timing one generated input of a loop-style test."""

    def __init__(self, test: str):
        self.test = test

    def __enter__(self) -> Timer:
        self.t0 = time.perf_counter()
        return self

    def __exit__(self, *exc: object) -> None:
        record(self.test, 1, time.perf_counter() - self.t0)


def _on_observation(obs: Any) -> None:
    if getattr(obs, "type", None) != "test_case" or obs.status == "gave_up":
        return
    t = sum(v for k, v in obs.timing.items() if k.startswith("execute:"))
    record(obs.property, 1, float(t), str(obs.representation))


def _worker_file() -> Path:
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    return Path(REPORT).with_suffix(f".{worker}.json")


def _peak_rss_bytes() -> int:
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(rss if sys.platform == "darwin" else rss * 1024)


def pytest_configure(config: pytest.Config) -> None:
    if not REPORT:
        return
    from hypothesis.internal.observability import add_observability_callback

    add_observability_callback(_on_observation)
    if not hasattr(config, "workerinput"):  # the controller: clear earlier workers' files
        for old in Path(REPORT).parent.glob(Path(REPORT).stem + ".*.json"):
            old.unlink()


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    if not REPORT:
        return
    Path(REPORT).parent.mkdir(parents=True, exist_ok=True)
    _worker_file().write_text(json.dumps({
        "counts": dict(_counts), "slowest_s": _slowest, "slowest_input": _slowest_input,
        "peak_rss_bytes": _peak_rss_bytes()}))
    if hasattr(session.config, "workerinput"):
        return
    counts: Counter[str] = Counter()
    slowest: dict[str, float] = {}
    slowest_input: dict[str, str] = {}
    peak = 0
    for part in sorted(Path(REPORT).parent.glob(Path(REPORT).stem + ".*.json")):
        d = json.loads(part.read_text())
        counts.update(d["counts"])
        for k, v in d["slowest_s"].items():
            if v >= slowest.get(k, 0.0):
                slowest[k] = v
                slowest_input[k] = d["slowest_input"].get(k, "")
        peak = max(peak, d["peak_rss_bytes"])
    over = {k: v for k, v in slowest.items() if v > LIMIT_S}
    summary = {"total_inputs": sum(counts.values()), "tests": len(counts),
               "per_test": dict(sorted(counts.items())),
               "slowest_s": max(slowest.values(), default=0.0),
               "slowest_per_test_s": {k: round(v, 3) for k, v in sorted(slowest.items())},
               "slowest_input": dict(sorted(slowest_input.items())),
               "over_time_limit": over, "time_limit_s": LIMIT_S,
               "peak_rss_bytes_per_process": peak}
    Path(REPORT).write_text(json.dumps(summary, indent=1) + "\n")
    session.config._fuzz_summary = summary  # type: ignore[attr-defined]
    if over and session.exitstatus == 0:
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


def pytest_terminal_summary(terminalreporter: Any, exitstatus: int, config: pytest.Config) -> None:
    s = getattr(config, "_fuzz_summary", None)
    if s is None:
        return
    terminalreporter.write_line(
        f"fuzz: {s['total_inputs']} generated inputs in {s['tests']} tests, slowest "
        f"{s['slowest_s']:.2f} s (limit {s['time_limit_s']:g} s, kernel loading "
        f"included), peak RSS per process "
        f"{s['peak_rss_bytes_per_process'] / 2**20:.0f} MiB; report {REPORT}")
    for k, v in s["over_time_limit"].items():
        terminalreporter.write_line(f"fuzz: OVER THE TIME LIMIT: {k} took {v:.2f} s")
