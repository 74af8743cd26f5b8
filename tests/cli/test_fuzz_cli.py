"""Fuzzing every CLI command's numeric options (hypothesis).

Each case is one option of one command, given arbitrary text: numbers of any
size and sign, floats with NaN and infinities, edge spellings (``1e309``,
``0x10``, ``1_000``, a 400-digit integer, Arabic digits, empty), and short
random text. The command must exit 0, 1 or 2, and on 2 print exactly one line
on stderr; anything else (a traceback, another exit code) fails. Every run is
kept short by small budgets placed before the fuzzed option (argparse keeps
the last value). A work-size option (``--n``, ``--repeats``, ...) whose value
parses to more than a small cap is parsed but not run: a legitimately long
job is not a fuzzing result.

``make test`` runs :data:`QUICK` examples per option; ``make fuzz`` runs
``FUZZ_EXAMPLES // 10`` per option.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
from dataclasses import dataclass

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from subtask_opt.cli import build_parser, main

QUICK = 3
FUZZ_CLI = max(1, int(os.environ.get("FUZZ_EXAMPLES", "60")) // 10)

EDGES = ["", " ", "0", "-0", "1", "-1", "2", "3", "0.5", "1e-9", "1e-320", "1e308", "1e309",
         "-1e308", "nan", "NaN", "inf", "-inf", "Infinity", "0x10", "1_000", " 5", "5 ", "\u0663",
         "1,2", "1e3", str(2**63 - 1), str(2**63), str(2**64), "9" * 400, "--", "-", "+1", "1j",
         "True", "1e-4", "1e4", "100000"]

_NUMBER = st.one_of(st.integers(-2**70, 2**70).map(str),
                    st.floats(allow_nan=True, allow_infinity=True).map(repr),
                    st.sampled_from(EDGES), st.text(max_size=6))
_VALUES = {
    "num": _NUMBER,
    "xy": st.one_of(st.tuples(_NUMBER, _NUMBER).map(",".join), _NUMBER),
    "xyh": st.one_of(st.tuples(_NUMBER, _NUMBER, _NUMBER).map(",".join),
                     st.tuples(_NUMBER, _NUMBER).map(",".join), _NUMBER),
    "list": st.one_of(st.lists(_NUMBER, min_size=1, max_size=3).map(",".join), _NUMBER),
}


@dataclass(frozen=True)
class Case:
    """One option of one command: the fuzzed ``option``, the ``base`` argv, the kind of
    value, and for a work-size option its argparse ``dest`` and the largest value run."""

    base: tuple[str, ...]
    option: str
    kind: str = "num"
    dest: str = ""
    cap: float = 0.0

    @property
    def id(self) -> str:
        words = self.base[:2] if self.base[0] in ("plan", "bench") else self.base[:1]
        return "-".join(words) + self.option


SOLVE = ("solve", "--case", "square20", "--no-progress", "--quiet", "--max-generations", "3",
         "--time-limit", "2")
GRID = ("plan", "grid", "--map", "open", "--planner", "ga", "--generations", "3",
        "--time-limit", "2")
POLY = ("plan", "polygon", "--start", "20,20", "--goal", "320,320", "--planner", "pso",
        "--swarm", "5", "--iterations", "3", "--time-limit", "2", "--no-progress")
REACT = ("plan", "reactive", "--world", "simple", "--max-steps", "20", "--no-progress")
BREACT = ("bench", "reactive", "--n", "1", "--max-steps", "20", "--no-progress")
MAKLINK = ("bench", "maklink", "--runs", "1", "--iterations", "3", "--swarm", "5",
           "--no-progress")

CASES = [
    *(Case(SOLVE, o) for o in ("--case-seed", "--k", "--first", "--seed", "--max-generations",
                               "--time-limit", "--no-improvement", "--target",
                               "--certify-time-limit")),
    *(Case(SOLVE, o, "list") for o in ("--vmax", "--amax", "--jmax")),
    Case((*SOLVE, "--trajectory", "TRAJ"), "--dt"),
    *(Case(GRID, o) for o in ("--seed", "--generations", "--stall", "--time-limit")),
    *(Case(GRID, o, "xy") for o in ("--start", "--goal")),
    *(Case(POLY, o) for o in ("--seed", "--iterations", "--stall", "--time-limit")),
    Case(POLY, "--swarm", dest="swarm", cap=200),
    *(Case(POLY, o, "xy") for o in ("--start", "--goal")),
    *(Case(REACT, o) for o in ("--seed", "--noise", "--range", "--max-speed",
                               "--max-turn-rate", "--dt", "--max-steps")),
    Case(REACT, "--start", "xyh"),
    Case(REACT, "--goal", "xy"),
    *(Case(("plan", "agv"), o) for o in ("--seed", "--frames")),
    Case(("bench", "grid", "--repeats", "1", "--no-progress"), "--seed"),
    Case(("bench", "grid", "--no-progress"), "--repeats", dest="repeats", cap=1),
    *(Case(BREACT, o) for o in ("--seed", "--noise", "--range", "--max-speed",
                                "--max-turn-rate", "--dt")),
    Case(BREACT, "--n", dest="n", cap=2),
    Case(BREACT, "--max-steps", dest="max_steps", cap=300),
    *(Case(MAKLINK, o) for o in ("--seed", "--stall", "--time-limit")),
    Case(MAKLINK, "--runs", dest="runs", cap=2),
    Case(MAKLINK, "--swarm", dest="swarm", cap=50),
    Case(MAKLINK, "--iterations", dest="iterations", cap=50),
    Case(("bench", "agv", "--n", "1", "--no-progress"), "--seed"),
    Case(("bench", "agv", "--no-progress"), "--n", dest="n", cap=2),
    Case(("tsp", "TSP", "--time-limit", "1", "--no-progress"), "--seed"),
    Case(("tsp", "TSP", "--no-progress"), "--time-limit", dest="time_limit", cap=2),
    *(Case(("batch", "MISSING.csv", "--workers", "1", "--no-progress"), o)
      for o in ("--seed", "--workers", "--max-generations", "--time-limit", "--no-improvement")),
]

TSP = ("NAME: tiny\nTYPE: TSP\nDIMENSION: 5\nEDGE_WEIGHT_TYPE: EUC_2D\nNODE_COORD_SECTION\n"
       "1 0 0\n2 10 0\n3 10 10\n4 0 10\n5 5 3\nEOF\n")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Paths the bases refer to: a TSPLIB file, a trajectory output, a missing manifest."""
    d = tmp_path_factory.mktemp("cli-fuzz")
    (d / "tiny.tsp").write_text(TSP)
    return {"TSP": str(d / "tiny.tsp"), "TRAJ": str(d / "traj.csv"),
            "MISSING.csv": str(d / "missing.csv")}


def _argv(case: Case, value: str, files: dict[str, str]) -> list[str]:
    return [files.get(a, a) for a in case.base] + [f"{case.option}={value}"]


def _too_big(case: Case, argv: list[str]) -> bool:
    """A work-size value above the case's cap (parsed, so parsing itself is fuzzed)."""
    if not case.dest:
        return False
    with contextlib.redirect_stderr(io.StringIO()):
        try:
            ns = build_parser().parse_args(argv)
        except SystemExit:
            return False
    v = getattr(ns, case.dest, None)
    return isinstance(v, int | float) and v > case.cap


def _run(case: Case, value: str, files: dict[str, str]) -> None:
    argv = _argv(case, value, files)
    assume(not _too_big(case, argv))
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    lines = err.getvalue().strip().splitlines()
    assert code in (0, 1, 2), (argv, code)
    if code != 0:
        assert len(lines) == 1, (argv, lines)
    assert not any("Traceback" in ln for ln in lines), (argv, lines)


def _fuzz(case: Case, files: dict[str, str], examples: int, *, derandomize: bool) -> None:
    """``examples`` hypothesis values for ``case``; the property is named after the case
    (so a fuzz run's report counts each option apart)."""

    def check(value: str) -> None:
        _run(case, value, files)

    check.__name__ = check.__qualname__ = "cli_" + re.sub(r"\W", "_", case.id)
    settings(max_examples=examples, deadline=None, derandomize=derandomize,
             database=None if derandomize else settings.default.database,
             suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])(
        given(value=_VALUES[case.kind])(check))()


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_cli_numeric_options(case, files):
    _fuzz(case, files, QUICK, derandomize=True)


@pytest.mark.fuzz
@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_fuzz_cli_numeric_options(case, files):
    _fuzz(case, files, FUZZ_CLI, derandomize=False)


def test_every_case_names_an_option_its_command_has():
    parser = build_parser()
    for case in CASES:
        command = list(case.base[:2] if case.base[0] in ("plan", "bench") else case.base[:1])
        help_text = io.StringIO()
        with contextlib.redirect_stdout(help_text), pytest.raises(SystemExit) as exc:
            parser.parse_args([*command, "--help"])
        assert exc.value.code == 0
        assert case.option in help_text.getvalue(), case.id
