"""A few dozen generated bad inputs of every class of the campaign (``tests/cli/campaign.py``;
the script itself runs thousands): each must exit 2 (a batch's bad job file: 1) with one
line, no traceback, no hang, no crash, inputs untouched, no partial output; each API call
must raise ParameterError or InputDataError.

Plus the two failures the campaign cannot provoke before the work starts: a disk that fills
up while an output is written (``RLIMIT_FSIZE``, as a full disk: the write fails) and a file
swapped for a FIFO between the check and the read.
"""

from __future__ import annotations

import os
import random
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pytest

from subtask_opt.base.errors import InputDataError, ParameterError
from subtask_opt.base.files import atomic_output, check_output, read_text
from tests.cli import campaign

PER_CLASS = 30
FAMILIES = ("option", "input", "output", "content", "precedence", "number", "api")
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def fixtures():
    with campaign.fixtures() as fx:
        campaign.preload()
        yield fx


def _sample(fx: campaign.Fixtures, family: str) -> list[campaign.Attempt]:
    by_class: dict[str, list[campaign.Attempt]] = defaultdict(list)
    for a in campaign.generate(fx, 0, seed=0):
        if a.klass.split(":")[0] == family:
            by_class[a.klass].append(a)
    rng = random.Random(family)
    picked: list[campaign.Attempt] = []
    classes = sorted(by_class)
    while len(picked) < PER_CLASS and any(by_class.values()):
        for k in classes:
            if by_class[k] and len(picked) < PER_CLASS:
                picked.append(by_class[k].pop(rng.randrange(len(by_class[k]))))
    return picked


@pytest.mark.parametrize("family", FAMILIES)
def test_every_class_of_bad_input_is_refused_in_one_line(fixtures, family):
    attempts = _sample(fixtures, family)
    assert len(attempts) >= min(PER_CLASS, 5), family
    # 120 s: a guard against a hang, not a timing (a refused input takes milliseconds)
    outcomes = campaign.run(attempts, fixtures, time_cap=120.0, warm_up=False)
    bad = [(o.problems, o.attempt.label, o.code, o.stderr[-300:]) for o in outcomes
           if o.problems]
    assert not bad, bad


def test_every_option_of_every_command_is_in_the_campaign():
    """A new option gets bad values in the campaign (or is a flag or an input/output)."""
    kinds = campaign._option_kinds()
    with campaign.fixtures() as fx:
        commands = campaign.commands(fx)
    covered = {" ".join(c.base[:2] if c.base[0] in ("plan", "bench") else c.base[:1])
               for c in commands}
    assert {k[0] for k in kinds} <= covered


def test_a_disk_that_fills_up_during_the_write_leaves_no_file(tmp_path):
    out = tmp_path / "out.json"
    warm = tmp_path.parent / f"{tmp_path.name}-warm.json"
    # the kernels compiled and cached first: numba's cache files must not hit the limit
    code = ("import resource, sys; from subtask_opt.cli import main; "
            f"main(['plan', 'grid', '--map', 'open', '--planner', 'dt', '--json', {str(warm)!r}]); "
            "resource.setrlimit(resource.RLIMIT_FSIZE, (2048, 2048)); "
            f"sys.exit(main(['plan', 'grid', '--map', 'open', '--planner', 'dt', '--json', "
            f"{str(out)!r}]))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=str(ROOT)), timeout=600)
    lines = [ln for ln in done.stderr.splitlines() if not ln.startswith("subtask-opt: comp")]
    assert done.returncode == 2, done.stderr
    assert len(lines) == 1 and str(out) in lines[0] and "File too large" in lines[0]
    assert list(tmp_path.iterdir()) == []  # neither the file nor its temporary name


def test_atomic_output_keeps_the_old_file_when_the_writer_fails(tmp_path):
    out = tmp_path / "a.json"
    out.write_text("old")
    with pytest.raises(RuntimeError), atomic_output(out) as tmp:
        tmp.write_text("half")
        raise RuntimeError("the figure failed")
    assert out.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]


@pytest.mark.parametrize("path", ["-", "", "/dev/full", "/dev/null", "/proc/x/y.json"])
def test_check_output_refuses_what_cannot_be_a_file(path):
    with pytest.raises(ParameterError):
        check_output(path)


def test_check_output_refuses_folders_and_paths_below_files(tmp_path):
    (tmp_path / "f").write_text("")
    for path in (tmp_path, tmp_path / "f" / "x.json"):
        with pytest.raises(ParameterError, match=str(path.parent if path != tmp_path
                                                     else path)):
            check_output(path)
    assert check_output(tmp_path / "new" / "deeper" / "x.json")  # created when written


@pytest.mark.parametrize("special", ["fifo", "/dev/zero", "/dev/urandom", "/dev/stdin"])
def test_read_text_refuses_fifos_and_devices_without_blocking(tmp_path, special):
    path = Path(special)
    if special == "fifo":
        path = tmp_path / "f.csv"
        os.mkfifo(path)
    with pytest.raises(InputDataError, match="pipe|device|regular"):
        read_text(path, "subtask file")


def test_read_text_refuses_binary_and_reads_at_most_the_limit(tmp_path):
    (tmp_path / "b.csv").write_bytes(b"x,y\n\x00\x01")
    with pytest.raises(InputDataError, match="binary"):
        read_text(tmp_path / "b.csv", "subtask file")
    big = tmp_path / "big.csv"
    with open(big, "wb") as fh:
        fh.truncate(1 << 30)  # sparse: the size check refuses it before any read
    with pytest.raises(InputDataError, match="limit"):
        read_text(big, "subtask file", max_bytes=1 << 20)


@pytest.mark.parametrize("digit", ["\u0663", "\u00b3", "\uff13", "\U0001d7db"])
def test_non_ascii_digits_are_not_numbers_in_any_reader(tmp_path, digit):
    from subtask_opt.arm.poses import load_targets
    from subtask_opt.arm.tasks import load_subtasks
    from subtask_opt.planners.grid.world import GridWorld
    from subtask_opt.tour.tsplib import parse_tsplib

    (tmp_path / "s.csv").write_text(f"x,y\n0.3,{digit}\n", encoding="utf-8")
    with pytest.raises(InputDataError, match="line 2"):
        load_subtasks(tmp_path / "s.csv")
    (tmp_path / "t.csv").write_text(f"x,y,z,dx,dy,dz\n0.4,0,0.2,1,0,{digit}\n",
                                    encoding="utf-8")
    with pytest.raises(InputDataError, match="row 1"):
        load_targets(tmp_path / "t.csv")
    with pytest.raises(InputDataError, match="line 3"):
        parse_tsplib(f"NAME: x\nTYPE: TSP\nDIMENSION: {digit}\nEOF\n")
    (tmp_path / "m.map").write_text(f"type octile\nheight {digit}\nwidth 2\nmap\n..\n..\n",
                                    encoding="utf-8")
    with pytest.raises(InputDataError, match="height"):
        GridWorld.from_movingai(tmp_path / "m.map")
