"""The bad-input campaign: every command x every option family, and the public API, given
bad values under a memory cap and a time cap; a table of what went wrong.

Run it (``make campaign``; about ten minutes on two cores for 3,000 attempts)::

    python -m tests.cli.campaign --attempts 3000 --seed 0 [--json out/campaign.json]

Every attempt is one command line (or one API call) with one bad value: a number out
of the option's stated bound or not a number at all, a choice that is not one, an input
file that is a FIFO, a device, a folder, missing, huge, binary or malformed in one of many
ways, an output path that is a folder, ``-``, a device, an input, below a file, in a
read-only or a full folder. The command must exit 2 with exactly one line on stderr
(1 when the job ran and failed), never print a traceback, never be killed by a signal
(``crashes``), finish within the time cap (``hangs``), leave its inputs as they were and
leave no partial output behind. An API call must raise ParameterError or InputDataError.

Each attempt runs in a child forked from a process that has imported the package once
(so an attempt costs milliseconds, not an interpreter start), with ``RLIMIT_AS`` set as
``prlimit --as`` would and its stdout/stderr captured. The table's columns:

* ``tracebacks``: "Traceback" on stderr, or an uncaught exception;
* ``hangs``: still running at the time cap (killed);
* ``crashes``: killed by a signal (a segfault, an abort, the memory cap's SIGKILL);
* ``wrong exits``: an exit code other than 2 for bad input (1 counts only for a job that
  ran and failed), more or fewer than one stderr line, an API exception of another type;
* ``silent accepts``: exit 0 (or an API call that returned) for a bad value;
* ``inputs changed``, ``partial outputs``: an input file whose bytes changed, an output
  file or a temporary ``.part`` file left after a refused run.

``tests/cli/test_campaign.py`` runs a few dozen attempts of every class in the unit
tests; this script runs thousands.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import math
import os
import random
import resource
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from collections import Counter, defaultdict
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

COLUMNS = ("tracebacks", "hangs", "crashes", "wrong exits", "silent accepts",
           "inputs changed", "partial outputs")
MEMORY_CAP = 3 << 30
"""``RLIMIT_AS`` of every attempt (numba and LLVM reserve about 1 GiB of address space)."""
TIME_CAP_S = 30.0


@dataclass(frozen=True)
class Attempt:
    """One command line (``argv``) or one API call (``call``: a name of :data:`API`).

    ``klass`` names the class of bad input; ``outputs`` are the paths that must not
    exist after the attempt (a refused output); ``ok_codes`` the exit codes that are right.
    """

    klass: str
    argv: tuple[str, ...] = ()
    call: str = ""
    args: tuple[Any, ...] = ()
    outputs: tuple[str, ...] = ()
    ok_codes: tuple[int, ...] = (2,)

    @property
    def label(self) -> str:
        if self.call:
            return f"api {self.call}{self.args!r}"[:160]
        return " ".join(a if len(a) < 60 else a[:57] + "..." for a in self.argv)


@dataclass
class Outcome:
    attempt: Attempt
    problems: list[str] = field(default_factory=list)
    code: int | None = None
    stderr: str = ""
    seconds: float = 0.0


# ----------------------------------------------------------------------------- fixtures

TSP = ("NAME: ring\nTYPE: TSP\nDIMENSION: 8\nEDGE_WEIGHT_TYPE: EUC_2D\nNODE_COORD_SECTION\n"
       + "".join(f"{i + 1} {round(100 * math.cos(i)):d} {round(100 * math.sin(i)):d}\n"
                 for i in range(8)) + "EOF\n")
GTSP = ("NAME: ring\nTYPE: GTSP\nDIMENSION: 8\nGTSP_SETS: 4\nEDGE_WEIGHT_TYPE: EUC_2D\n"
        "NODE_COORD_SECTION\n"
        + "".join(f"{i + 1} {round(100 * math.cos(i)):d} {round(100 * math.sin(i)):d}\n"
                  for i in range(8))
        + "GTSP_SET_SECTION\n" + "".join(f"{k + 1} {2 * k + 1} {2 * k + 2} -1\n"
                                          for k in range(4)) + "EOF\n")
UR5_TARGETS = ("x,y,z,dx,dy,dz\n0.45,-0.15,0.20,1,0,-0.3\n0.45,0.05,0.20,1,0,-0.3\n"
               "0.42,-0.10,0.35,1,0,-0.3\n0.40,0.10,0.30,1,0,-0.3\n")
SUBTASKS = "x,y\n" + "".join(f"{0.3 + 0.05 * (i % 4)},{0.1 * (i // 4) - 0.2}\n"
                             for i in range(8))
HUGE_BYTES = 100 << 20


class Fixtures:
    """The files of the campaign in one temporary folder: good inputs the bases use, bad
    inputs (special files, malformed contents) and places for bad outputs."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.mounts: list[Path] = []
        w = self.write
        self.good = {
            "sub.csv": w("sub.csv", SUBTASKS),
            "t3d.csv": w("t3d.csv", UR5_TARGETS),
            "ring.tsp": w("ring.tsp", TSP),
            "ring.gtsp": w("ring.gtsp", GTSP),
            "prec.txt": w("prec.txt", "0,1\n2,3\n"),
            "scene.json": w("scene.json", '{"boxes": []}\n'),
            "manifest.json": w("manifest.json", '[{"id": "a", "case": "square20"}]\n'),
            "limits.json": w("limits.json", '{"velocity": [3, 3, 3, 3, 3, 3]}\n'),
        }
        data = Path(__file__).resolve().parents[3] / "shared" / "data" / "movingai"
        if not data.is_dir():
            data = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "movingai"
        self.movingai = (data / "maps" / "arena.map", data / "scenarios" / "arena.map.scen")
        self.checksums: dict[Path, str] = {}

    def write(self, name: str, text: str | bytes) -> str:
        path = self.root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(text, bytes):
            path.write_bytes(text)
        else:
            path.write_text(text, encoding="utf-8", errors="surrogatepass")
        return str(path)

    def special_inputs(self, suffix: str) -> list[tuple[str, str]]:
        """``(class, path)`` of inputs that are no regular text file, named ``*suffix``."""
        r = self.root
        out = []
        fifo = r / f"fifo{suffix}"
        if not fifo.exists():
            os.mkfifo(fifo)
        out.append(("input: fifo", str(fifo)))
        folder = r / f"folder{suffix}"
        folder.mkdir(exist_ok=True)
        out.append(("input: folder", str(folder)))
        out.append(("input: missing", str(r / "no" / f"missing{suffix}")))
        huge = r / f"huge{suffix}"
        if not huge.exists():
            with open(huge, "wb") as fh:
                fh.truncate(HUGE_BYTES)  # sparse: no disk used
        out.append(("input: huge", str(huge)))
        out.append(("input: binary", self.write(f"binary{suffix}", random.Random(0).randbytes(
            4096) + b"\x00")))
        out.append(("input: utf-16", self.write(f"utf16{suffix}", "x,y\n1,2\n".encode(
            "utf-16"))))
        for dev in ("/dev/zero", "/dev/urandom", "/dev/null", "/dev/stdin"):
            out.append(("input: device", dev))
        link = r / f"loop{suffix}"
        if not link.is_symlink():
            os.symlink(link, link)
        out.append(("input: symlink loop", str(link)))
        return out

    def bad_outputs(self, suffix: str, an_input: str) -> list[tuple[str, str]]:
        """``(class, path)`` of outputs that cannot be written, ending in ``suffix``."""
        r = self.root
        folder = r / f"outdir{suffix}"
        folder.mkdir(exist_ok=True)
        below = Path(self.good["sub.csv"]) / f"x{suffix}"
        out = [("output: folder", str(folder)), ("output: dash", "-"),
               ("output: device", "/dev/full"), ("output: device", "/dev/null"),
               ("output: below a file", str(below)),
               ("output: unwritable folder", f"/proc/subtask-opt-campaign/x{suffix}"),
               ("output: unwritable folder", f"/proc/x{suffix}"),
               ("output: equal to an input", an_input)]
        fifo = r / f"outfifo{suffix}"
        if not fifo.exists():
            os.mkfifo(fifo)
        out.append(("output: fifo", str(fifo)))
        for kind in ("ro", "full"):
            mount = self.mount(kind)
            if mount is not None:
                out.append((f"output: {'read-only' if kind == 'ro' else 'full'} folder",
                            str(mount / "sub" / f"x{suffix}")))
                out.append((f"output: {'read-only' if kind == 'ro' else 'full'} folder",
                            str(mount / f"x{suffix}")))
        return out

    def mount(self, kind: str) -> Path | None:
        """A read-only (``ro``) or full (``full``) tmpfs, or None where mounting fails."""
        path = self.root / f"mnt-{kind}"
        if path in self.mounts:
            return path
        path.mkdir(exist_ok=True)
        options = "size=64k,ro" if kind == "ro" else "size=64k"
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)],
                              capture_output=True, check=False)
        if done.returncode != 0:
            return None
        self.mounts.append(path)
        if kind == "full":  # fill it: the probe may still create a name, the write fails
            with contextlib.suppress(OSError), open(path / "filler", "wb") as fh:
                fh.write(b"\0" * (64 << 10))
        return path

    def snapshot(self) -> None:
        self.checksums = {p: _digest(p) for p in self.root.rglob("*")
                          if p.is_file() and not p.is_symlink() and "huge" not in p.name
                          and not any(m in p.parents for m in self.mounts)
                          and self.root / "outputs" not in p.parents}

    def changed(self) -> list[str]:
        return [str(p) for p, d in self.checksums.items() if _digest(p) != d]

    def leftovers(self) -> list[str]:
        return [str(p) for p in self.root.rglob("*.part*")] + [
            str(p) for p in self.root.rglob(".subtask-opt-probe-*")]

    def close(self) -> None:
        for m in self.mounts:
            subprocess.run(["umount", str(m)], capture_output=True, check=False)


def _digest(path: Path) -> str:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return "gone"


# ------------------------------------------------------------------------- bad values

NUMBERS = ["nan", "NaN", "inf", "-inf", "Infinity", "1e309", "-1e309", "9" * 5000,
           "-" + "9" * 5000, "1e20", "-1e20", str(2**64), str(-2**64), "1e400", "\u0663",
           "\u00b2", "\uff11", "\u0661\u0660", "0x10", "", " ", "abc", "1e", "--", "None",
           "1j", "True", "1,2,3,4,5,6,7,8,9", "\U0001d7d9", "1e-400x"]
"""Values every numeric option refuses: not finite, not ASCII, not a number, or above
1e19 (every option's stated bound is below)."""
POINTS = ["1e20,1e20", "nan,0", "0,inf", "1", "1,2,3,4", "\u0663,\u0663", "1e309,0", ",",
          "9" * 5000 + ",0", "a,b", ""]
CHOICES = ["nope", "", "JOINT", "\uff4a\uff4f\uff49\uff4e\uff54", "joint ", "-1"]
TOOL_FRAMES = ["universe", "", "no_such_frame", "x" * 5000, "\udc80"]
SCHEDULERS = ["nonsense", "tcp://", "tcp://127.0.0.1:1", "", "\U0001f600://x"]


def malformed(kind: str, rng: random.Random) -> list[tuple[str, str | bytes]]:
    """``(class, content)`` of malformed files of one input ``kind``."""
    digits = "9" * 5000
    out: list[tuple[str, str | bytes]] = [
        ("content: empty", ""), ("content: blank", "\n\n  \n"),
        ("content: garbage", "".join(rng.choice("ab,;:{}[]\"'\\ \n\t0123456789.-e")
                                      for _ in range(rng.randint(1, 400)))),
        ("content: invalid utf-8", bytes(rng.randint(128, 255) for _ in range(64))),
        ("content: long line", "x" * 2_000_000),
    ]
    if kind in ("csv", "t3d"):
        header = "x,y" if kind == "csv" else "x,y,z,dx,dy,dz"
        width = 2 if kind == "csv" else 6
        row = ",".join(["0.4"] * width)
        out += [
            ("content: csv field over the limit", f'{header}\n"' + "1" * 200_000 + '"\n'),
            ("content: csv open quote", f'{header}\n"' + ("1\n" * 90_000)),
            ("content: 5000-digit number", f"{header}\n{digits}," + ",".join(
                ["0.1"] * (width - 1)) + "\n"),
            ("content: non-ASCII digits", f"{header}\n\u0663," + ",".join(
                ["0.1"] * (width - 1)) + "\n"),
            ("content: nan", f"{header}\nnan," + ",".join(["0.1"] * (width - 1)) + "\n"),
            ("content: header only", header + "\n"),
            ("content: wrong width", f"{header}\n1\n"),
            ("content: large case", header + "\n" + (row + "\n") * 200_000),
            ("content: duplicate rows", header + "\n" + (row + "\n") * 3),
        ]
    if kind == "json":
        out += [
            ("content: lone surrogate", '{"points": [[0.4, 0.1], [0.4, 0.2]], "name": '
                                        '"\\ud800"}'),
            ("content: lone surrogate", '{"targets": [{"position": [0.4, 0, 0.2], "axis": '
                                        '[1, 0, 0], "name": "\\udfff"}]}'),
            ("content: deep nesting", "[" * 100_000 + "]" * 100_000),
            ("content: 5000-digit number", '{"points": [[' + digits + ", 0]]}"),
            ("content: NaN", '{"points": [[NaN, 0]]}'),
            ("content: 1e999", '{"points": [[1e999, 0]]}'),
            ("content: wrong types", '{"points": "abc"}'),
            ("content: large case", '{"points": [' + ",".join(["[0.4, 0.1]"] * 300_000)
             + "]}"),
        ]
    if kind == "gtsp":
        out += [
            ("content: gtsp huge dimension", GTSP.replace("DIMENSION: 8",
                                                          "DIMENSION: 100000000000")),
            ("content: gtsp 5000-digit sets", GTSP.replace("GTSP_SETS: 4",
                                                           "GTSP_SETS: " + digits)),
            ("content: gtsp vertex in two sets", GTSP.replace("2 3 4 -1", "2 3 1 -1")),
            ("content: gtsp set without -1", GTSP.replace("4 7 8 -1", "4 7 8")),
            ("content: gtsp no sets", GTSP.split("GTSP_SET_SECTION")[0] + "EOF\n"),
            ("content: gtsp nan coordinate", GTSP.replace("1 100 0", "1 nan 0")),
        ]
    if kind == "tsp":
        out += [
            ("content: tsp huge dimension", TSP.replace("DIMENSION: 8",
                                                        "DIMENSION: 100000000000")),
            ("content: tsp 5000-digit dimension", TSP.replace("DIMENSION: 8",
                                                              "DIMENSION: " + digits)),
            ("content: tsp explicit huge", "NAME: x\nTYPE: TSP\nDIMENSION: 90000\n"
             "EDGE_WEIGHT_TYPE: EXPLICIT\nEDGE_WEIGHT_FORMAT: FULL_MATRIX\n"
             "EDGE_WEIGHT_SECTION\n1 2 3\nEOF\n"),
            ("content: tsp nan coordinate", TSP.replace("1 100 0", "1 nan 0")),
            ("content: tsp non-ASCII digits", TSP.replace("DIMENSION: 8", "DIMENSION: \u0668")),
            ("content: tsp truncated", TSP[: len(TSP) // 2]),
        ]
    if kind == "prec":
        out += [
            ("precedence: cycle", "0,1\n1,2\n2,0\n"),
            ("precedence: long cycle", "".join(f"{i},{i + 1}\n" for i in range(15)) + "15,0\n"),
            ("precedence: self-loop", "3,3\n"),
            ("precedence: duplicate", "0,1\n0,1\n"),
            ("precedence: out of range", "0,99\n"),
            ("precedence: superscript", "0,\u00b2\n"),
            ("precedence: Arabic-Indic", "\u0660,\u0661\n"),
            ("precedence: full-width", "\uff10,\uff11\n"),
            ("precedence: 5000 digits", f"0,{digits}\n"),
            ("precedence: negative", "-1,2\n"),
            ("precedence: three", "1,2,3\n"),
        ]
    if kind == "scene":
        out += [
            ("content: lone surrogate", '{"boxes": [{"name": "\\udc00", "center": [1, 1, 1], '
                                        '"half_extents": [0.1, 0.1, 0.1]}]}'),
            ("content: deep nesting", '{"boxes": ' + "[" * 10_000 + "]" * 10_000 + "}"),
            ("content: 5000-digit number", '{"boxes": [{"name": "b", "center": [' + digits
             + ', 1, 1], "half_extents": [0.1, 0.1, 0.1]}]}'),
            ("content: many boxes", '{"boxes": [' + ",".join(
                '{"name": "b", "center": [2, 2, 2], "half_extents": [0.01, 0.01, 0.01]}'
                for _ in range(50_000)) + "]}"),
        ]
    if kind == "limits":
        out += [
            ("content: lone surrogate", '{"velocity": [1, 1, 1, 1, 1, 1], "\\ud801": 1}'),
            ("content: 5000-digit number", '{"velocity": [' + digits + ", 1, 1, 1, 1, 1]}"),
            ("content: wrong length", '{"velocity": [1, 2]}'),
            ("content: deep nesting", "[" * 100_000 + "]" * 100_000),
        ]
    if kind == "manifest":
        out += [
            ("content: lone surrogate", '[{"id": "\\ud800", "case": "square20"}]'),
            ("content: 5000-digit seed", '[{"id": "a", "case": "square20", "seed": '
             + digits + "}]"),
            ("content: unknown key", '[{"id": "a", "case": "square20", "x": 1}]'),
            ("content: duplicate ids", '[{"id": "a", "case": "square20"}, {"id": "a", '
                                       '"case": "random30"}]'),
            ("content: deep nesting", "[" * 100_000 + "]" * 100_000),
        ]
    if kind == "urdf":
        out += [
            ("content: bad xml", "<robot name='x'><link name='a'>"),
            ("content: billion laughs", '<?xml version="1.0"?><!DOCTYPE l [<!ENTITY a "aaaa">'
             + "".join(f'<!ENTITY {chr(98 + i)} "' + f"&{chr(97 + i)};" * 10 + '">'
                       for i in range(8)) + "]><robot name='&i;'/>"),
            ("content: no joints", "<robot name='x'><link name='a'/></robot>"),
        ]
    if kind in ("world", "scenario"):
        out += [
            ("content: lone surrogate", '{"name": "\\ud800", "obstacles": []}'),
            ("content: deep nesting", "[" * 100_000 + "]" * 100_000),
            ("content: 5000-digit number", '{"width": ' + digits + "}"),
        ]
    if kind == "map":
        out += [
            ("content: huge map header", "type octile\nheight 100000000\nwidth 100000000\nmap\n"
             "....\n"),
            ("content: 5000-digit size", f"type octile\nheight {digits}\nwidth 4\nmap\n....\n"),
            ("content: ragged map", "type octile\nheight 3\nwidth 4\nmap\n....\n..\n"),
            ("content: non-ASCII digits", "type octile\nheight \u0662\nwidth 2\nmap\n..\n..\n"),
        ]
    return out


# ------------------------------------------------------------------------ generation

@dataclass(frozen=True)
class Command:
    """A command's valid, cheap base argv and what its options are."""

    name: str
    base: tuple[str, ...]
    inputs: dict[str, str]  # option (or "" for the positional) -> malformed kind
    outputs: dict[str, str]  # option -> suffix
    an_input: tuple[str, str] = ("", "")  # an input option and a good file for it


def commands(fx: Fixtures) -> list[Command]:
    g = fx.good
    ma, ms = (str(p) for p in fx.movingai)
    return [
        Command("solve", ("solve", "--case", "square20", "--no-progress", "--quiet",
                          "--max-generations", "3"),
                {"--case": "csv", "--precedence": "prec", "--robot": "urdf"},
                {"--json": ".json", "--plot": ".png", "--trajectory": ".csv",
                 "--animate": ".gif"}, ("--case", g["sub.csv"])),
        Command("solve serial", ("solve", "--robot", "ur5", "--case", g["t3d.csv"],
                                 "--home", "0,-90,90,-90,-90,0", "--no-progress", "--quiet",
                                 "--max-generations", "3"),
                {"--case": "t3d", "--scene": "scene", "--limits": "limits",
                 "--robot": "urdf"},
                {"--json": ".json", "--view": ".html", "--trajectory": ".csv",
                 "--plot": ".png"}, ("--scene", g["scene.json"])),
        Command("tsp", ("tsp", g["ring.tsp"], "--time-limit", "0.5", "--no-progress"),
                {"": "tsp"}, {"--json": ".json", "--plot": ".png"}, ("", g["ring.tsp"])),
        Command("gtsp", ("gtsp", g["ring.gtsp"], "--time-limit", "0.5", "--no-progress"),
                {"": "gtsp"}, {"--json": ".json", "--plot": ".png"}, ("", g["ring.gtsp"])),
        Command("batch", ("batch", g["sub.csv"], "--workers", "0", "--max-generations", "3",
                          "--no-progress", "--json", str(fx.root / "outputs" / "batch.json")),
                {"": "csv", "--scene": "scene"}, {"--json": ".json", "--plot": ".png"},
                ("", g["sub.csv"])),
        Command("batch manifest", ("batch", g["manifest.json"], "--workers", "0",
                                   "--max-generations", "3", "--no-progress", "--json",
                                   str(fx.root / "outputs" / "batch-m.json")),
                {"": "manifest"}, {}),
        Command("plan grid", ("plan", "grid", "--map", "open", "--planner", "dt"),
                {"--map": "map"}, {"--json": ".json", "--plot": ".png"}),
        Command("plan polygon", ("plan", "polygon", "--start", "20,20", "--goal", "320,320",
                                 "--planner", "visibility", "--no-progress"),
                {"--world": "world"}, {"--json": ".json", "--plot": ".png"}),
        Command("plan reactive", ("plan", "reactive", "--world", "simple", "--max-steps",
                                  "1000", "--no-progress"),
                {"--world": "world"}, {"--json": ".json", "--plot": ".png",
                                       "--animate": ".gif"}),
        Command("plan agv", ("plan", "agv", "--no-collision-check", "--frames", "4"),
                {"--scenario": "scenario"}, {"--json": ".json", "--plot": ".png",
                                             "--animate": ".gif"}),
        Command("bench grid", ("bench", "grid", "--repeats", "1", "--no-progress"), {},
                {"--json": ".json", "--plot": ".png"}),
        Command("bench movingai", ("bench", "movingai", "--map", ma, "--scen", ms,
                                   "--no-progress"),
                {"--map": "map", "--scen": "map"}, {"--json": ".json", "--plot": ".png"},
                ("--map", ma)),
        Command("bench maklink", ("bench", "maklink", "--runs", "1", "--iterations", "3",
                                  "--swarm", "5", "--no-progress"),
                {"--world": "world"}, {"--json": ".json", "--plot": ".png"}),
        Command("bench reactive", ("bench", "reactive", "--n", "1", "--max-steps", "20",
                                   "--workers", "0", "--no-progress"), {},
                {"--json": ".json", "--plot": ".png"}),
        Command("bench fuzzy-table", ("bench", "fuzzy-table"), {},
                {"--json": ".json", "--plot": ".png"}),
        Command("bench agv", ("bench", "agv", "--n", "1", "--workers", "0", "--no-progress"),
                {}, {"--json": ".json", "--plot": ".png"}),
        Command("bench robotsp", ("bench", "robotsp", "--sizes", "25"), {},
                {"--json": ".json"}),
        Command("reproduce", ("reproduce", "002", "--quick", "--no-progress", "--out",
                              str(fx.root / "outputs" / "papers")), {}, {"--out": ""}),
    ]


def _option_kinds() -> dict[tuple[str, str], tuple[str, Any]]:
    """``(command, option) -> (kind, choices)`` of every option of every command."""
    from subtask_opt.cli import build_parser

    kinds: dict[tuple[str, str], tuple[str, Any]] = {}

    def walk(parser: argparse.ArgumentParser, prefix: list[str]) -> None:
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        for a in subs:
            for name, sp in a.choices.items():
                walk(sp, [*prefix, name])
        if subs:
            return
        for a in parser._actions:
            if isinstance(a, argparse._HelpAction) or a.nargs == 0:
                continue
            opt = a.option_strings[0] if a.option_strings else ""
            tname = getattr(a.type, "__name__", "")
            if a.choices:
                kind = "choice"
            elif tname in ("point", "point3"):
                kind = "point"
            elif tname in ("int", "float", "seed", "floats", "signed_numbers", "_numbers"):
                kind = "number"
            elif a.dest == "tool_frame":
                kind = "tool_frame"
            elif a.dest == "scheduler":
                kind = "scheduler"
            else:
                kind = "text"
            kinds[(" ".join(prefix), opt)] = (kind, a.choices)

    walk(build_parser(), [])
    return kinds


def _with(base: tuple[str, ...], option: str, value: str) -> tuple[str, ...]:
    """``base`` with ``option`` set to ``value`` (replacing a positional when option is "")."""
    if option == "":
        words = list(base)
        words[2 if words[0] in ("plan", "bench") else 1] = value
        return tuple(words)
    if option in base:
        i = base.index(option)
        return (*base[:i + 1], value, *base[i + 2:])
    return (*base, f"{option}={value}" if value.startswith("-") else option, *(
        () if value.startswith("-") else (value,)))


def generate(fx: Fixtures, n: int, seed: int) -> list[Attempt]:
    """At least ``n`` attempts: the full grid of command x option x bad value, then
    random malformed contents and API calls until ``n``."""
    rng = random.Random(seed)
    kinds = _option_kinds()
    out: list[Attempt] = []
    for cmd in commands(fx):
        key = " ".join(cmd.base[:2] if cmd.base[0] in ("plan", "bench") else cmd.base[:1])
        for (command, option), (kind, _choices) in kinds.items():
            if command != key or option in cmd.inputs or option in cmd.outputs:
                continue
            values = {"number": NUMBERS, "point": POINTS, "choice": CHOICES,
                      "tool_frame": TOOL_FRAMES, "scheduler": SCHEDULERS}.get(kind)
            if values is None:
                continue
            if kind == "choice" and option == "":
                values = ["nope", "", "999", "\u0660\u0660\u0662"]
            for v in values:
                if kind == "tool_frame" and cmd.name != "solve serial" and option == \
                        "--tool-frame" and cmd.name.startswith("solve"):
                    continue
                out.append(Attempt(f"option: {kind}", _with(cmd.base, option, v)))
        for option, mkind in cmd.inputs.items():
            suffix = {"csv": ".csv", "t3d": ".csv", "tsp": ".tsp", "gtsp": ".gtsp",
                      "prec": ".txt", "scene": ".json", "limits": ".json",
                      "manifest": ".json", "json": ".json",
                      "urdf": ".urdf", "world": ".json", "scenario": ".json",
                      "map": ".map"}[mkind]
            job_file = cmd.name == "batch" and option == ""
            for klass, path in fx.special_inputs(suffix):
                regular = klass in ("input: huge", "input: binary", "input: utf-16")
                out.append(Attempt(klass, _with(cmd.base, option, path),
                                   ok_codes=(1,) if job_file and regular else (2,)))
            variants = malformed(mkind, rng)
            if mkind == "prec":  # an empty precedence file is no constraint: valid
                variants = [v for v in variants if v[0] not in ("content: empty",
                                                                 "content: blank")]
            if mkind == "csv" and option in ("--case", ""):
                variants += [(k, c) for k, c in malformed("json", rng)]
            for i, (klass, content) in enumerate(variants):
                ext = ".json" if mkind == "csv" and klass in {k for k, _ in malformed(
                    "json", random.Random(0))} and isinstance(content, str) and \
                    content.lstrip().startswith(("{", "[")) else suffix
                path = fx.write(f"bad/{cmd.name.replace(' ', '_')}{option}-{i}{ext}", content)
                # a batch reports a bad job file as that job's failure (exit 1), unless it
                # is no subtask file at all (a .json that is neither subtasks nor manifest)
                codes = (1, 2) if job_file and ext == ".json" else (1,) if job_file else (2,)
                out.append(Attempt(klass, _with(cmd.base, option, path), ok_codes=codes))
        in_option, in_file = cmd.an_input
        for option, suffix in cmd.outputs.items():
            for klass, path in fx.bad_outputs(suffix, in_file):
                base = cmd.base
                if klass == "output: equal to an input":
                    if not in_file or option == "--out":
                        continue
                    base = _with(base, in_option, in_file)
                if option == "--out" and klass == "output: folder":
                    klass, path = "output: a file for a folder", fx.good["prec.txt"]
                out.append(Attempt(klass, _with(base, option, path),
                                   outputs=(path,) if klass.endswith(" folder") and "file"
                                   not in klass else ()))
    if any(c.name == "solve serial" for c in commands(fx)):
        for step in ("1", "0.5", "2", "0.01", "1e-6"):
            out.append(Attempt("number: axis-step work",
                               _with(commands(fx)[1].base, "--axis-step", step)))
    out += api_attempts(fx)
    # more random malformed contents until n
    fill = [c for c in commands(fx) if c.inputs]
    k = 0
    while len(out) < n:
        cmd = rng.choice(fill)
        option, mkind = rng.choice(sorted(cmd.inputs.items()))
        suffix = {"csv": ".csv", "t3d": ".csv", "tsp": ".tsp", "gtsp": ".gtsp",
                  "prec": ".txt"}.get(mkind, ".json")
        if mkind in ("urdf",):
            suffix = ".urdf"
        if mkind == "map":
            suffix = ".map"
        content = _random_content(mkind, rng)
        path = fx.write(f"rand/{k}{suffix}", content)
        job_file = cmd.name == "batch" and option == ""
        out.append(Attempt("content: random", _with(cmd.base, option, path),
                           ok_codes=(0, 1, 2) if job_file else (0, 2)))
        k += 1
    return out


def _random_content(kind: str, rng: random.Random) -> str:
    """A random mutation of a valid file of ``kind``: characters dropped, repeated,
    replaced with digits, signs, quotes, non-ASCII digits, huge numbers."""
    valid = {"csv": SUBTASKS, "t3d": UR5_TARGETS, "tsp": TSP, "gtsp": GTSP,
             "prec": "0,1\n2,3\n",
             "scene": '{"boxes": [{"name": "b", "center": [2, 2, 2], "half_extents": '
                      '[0.1, 0.1, 0.1]}]}',
             "limits": '{"velocity": [3, 3, 3, 3, 3, 3]}',
             "manifest": '[{"id": "a", "case": "square20", "seed": 1}]',
             "urdf": "<robot name='x'><link name='a'/><link name='b'/><joint name='j' "
                     "type='revolute'><parent link='a'/><child link='b'/><limit lower='-1' "
                     "upper='1' velocity='1' effort='1'/></joint></robot>",
             "world": '{"name": "w", "width": 10, "height": 10, "obstacles": []}',
             "scenario": '{"name": "s"}', "map": "type octile\nheight 2\nwidth 2\nmap\n..\n..\n"
             }[kind]
    text = list(valid)
    junk = ["9" * rng.choice([30, 400, 5000]), "\u0663", "\u00b2", "-", '"', ",", "\n",
            "1e999", "nan", "{", "[", "\\ud800", "0" * 50, " ", "#", "\ufeff"]
    for _ in range(rng.randint(1, 6)):
        i = rng.randrange(len(text))
        op = rng.random()
        if op < 0.3:
            del text[i]
        elif op < 0.7:
            text.insert(i, rng.choice(junk))
        else:
            text[i] = rng.choice(junk)
    return "".join(text)


# ---------------------------------------------------------------------------- the API

def _api() -> dict[str, Callable[..., Any]]:
    import subtask_opt as so
    from subtask_opt.batch import Job, map_jobs, solve_many
    from subtask_opt.tour.tsplib import read_tsplib

    def arm_problem(case: Any, robot: Any = "planar_2r", **kw: Any) -> Any:
        return so.ArmProblem(so.load_targets(case), so.load_robot(robot), **kw)

    def solve_bad(**kw: Any) -> Any:
        problem = so.ArmProblem(so.builtin_case("square20", so.load_robot("planar_2r").model),
                                so.load_robot("planar_2r"))
        return so.solve(problem, **kw)

    return {"load_robot": so.load_robot, "load_targets": so.load_targets,
            "ArmProblem": arm_problem, "solve": solve_bad,
            "TourConstraints": so.TourConstraints, "SolverParams": so.SolverParams,
            "MaxGenerations": so.MaxGenerations, "MaxRuntime": so.MaxRuntime,
            "NoImprovement": so.NoImprovement, "TargetCost": so.TargetCost,
            "MatrixProblem": so.MatrixProblem, "held_karp": so.held_karp,
            "read_tsplib": read_tsplib, "Job": Job,
            "solve_many": lambda items, **kw: solve_many(items, seeds=0, workers=0, **kw),
            "map_jobs": lambda **kw: map_jobs(abs, [1], **kw),
            "read_precedence": _read_precedence}


def _read_precedence(path: Any, **kw: Any) -> Any:
    from subtask_opt.tour.constraints import read_precedence

    return read_precedence(path, **kw)


BAD = [float("nan"), float("inf"), -1, 10**30, "3", None, [1, 2], {"a": 1}, 1j, True,
       -(10**30), 1e-320, b"x", object]


def api_attempts(fx: Fixtures) -> list[Attempt]:
    out: list[Attempt] = []
    files = [p for _, p in fx.special_inputs(".csv")] + [p for _, p in fx.special_inputs(
        ".json")]
    for name in ("load_robot", "load_targets", "read_tsplib", "read_precedence"):
        for p in files:
            out.append(Attempt("api: file", call=name, args=(p,)))
    for v in BAD:
        out.append(Attempt("api: value", call="load_robot", args=(v,)))
        out.append(Attempt("api: value", call="TourConstraints", args=(("tour", v),)))
        out.append(Attempt("api: value", call="TourConstraints", args=(("precedence", v),)))
        out.append(Attempt("api: value", call="load_targets",
                           args=(fx.good["t3d.csv"], ("axis_step", v))))
        for stop in ("MaxGenerations", "MaxRuntime", "NoImprovement", "TargetCost"):
            # a time limit of 1e30 s or 1e-320 s, a target of -1 s: valid, if odd
            if stop in ("MaxRuntime", "TargetCost") and isinstance(v, (int, float)) and \
                    math.isfinite(v) and not isinstance(v, bool) and (v > 0 or stop ==
                                                                      "TargetCost"):
                continue
            out.append(Attempt("api: value", call=stop, args=(v,)))
        out.append(Attempt("api: value", call="MatrixProblem", args=(v,)))
        out.append(Attempt("api: value", call="held_karp", args=(v,)))
        out.append(Attempt("api: value", call="Job", args=(("id", "a"), ("case", "square20"),
                                                           ("seed", v))))
        if v is not None:  # workers=None and runs=None are the defaults
            out.append(Attempt("api: value", call="map_jobs", args=(("workers", v),)))
            out.append(Attempt("api: value", call="SolverParams", args=(("runs", v),)))
        out.append(Attempt("api: value", call="solve", args=(("seed", v),)))
        out.append(Attempt("api: value", call="solve_many", args=(v,)))
    for frame in TOOL_FRAMES:
        out.append(Attempt("api: tool frame", call="load_robot",
                           args=("ur5", ("tool_frame", frame))))
    return out


def _call(attempt: Attempt) -> None:
    fn = _api()[attempt.call]
    pos = [a for a in attempt.args if not (isinstance(a, tuple) and len(a) == 2
                                           and isinstance(a[0], str))]
    kw = dict(a for a in attempt.args if isinstance(a, tuple) and len(a) == 2
              and isinstance(a[0], str))
    fn(*pos, **kw)


# ---------------------------------------------------------------------------- running

def _child(attempt: Attempt, out_path: str, err_path: str, memory: int) -> None:
    """In the forked child: caps, redirections, the call; never returns."""
    code = 99
    try:
        os.setsid()
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
        fd_in = os.open(os.devnull, os.O_RDONLY)
        os.dup2(fd_in, 0)
        for fd, path in ((1, out_path), (2, err_path)):
            f = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
            os.dup2(f, fd)
            os.close(f)
        sys.stdin = open(0, closefd=False)  # noqa: SIM115
        sys.stdout = io.TextIOWrapper(open(1, "wb", closefd=False), write_through=True)
        sys.stderr = io.TextIOWrapper(open(2, "wb", closefd=False), write_through=True,
                                      errors="backslashreplace")
        if attempt.call:
            from subtask_opt.base.errors import InputDataError, ParameterError

            try:
                _call(attempt)
                code = 0
            except (ParameterError, InputDataError) as exc:
                print(f"api: {type(exc).__name__}: {exc}", file=sys.stderr)
                code = 2
            except BaseException as exc:  # noqa: BLE001 - another type is the finding
                print(f"api: wrong type {type(exc).__name__}: {exc}", file=sys.stderr)
                code = 3
        else:
            from subtask_opt.cli import main

            code = main(list(attempt.argv))
    except SystemExit as exc:
        code = int(exc.code) if isinstance(exc.code, int) else 98
    except BaseException:  # noqa: BLE001
        traceback.print_exc()
        code = 97
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code)


def run_attempt(attempt: Attempt, fx: Fixtures, *, time_cap: float = TIME_CAP_S,
                memory: int = MEMORY_CAP) -> Outcome:
    """Run one attempt in a forked child and judge it."""
    outcome = Outcome(attempt)
    for p in attempt.outputs:
        with contextlib.suppress(OSError):
            if Path(p).is_file():
                Path(p).unlink()
    with tempfile.TemporaryDirectory(prefix="campaign-io-") as tmp:
        out_path, err_path = f"{tmp}/out", f"{tmp}/err"
        sys.stdout.flush()
        sys.stderr.flush()
        start = time.monotonic()
        pid = os.fork()
        if pid == 0:
            os.chdir(fx.root)
            _child(attempt, out_path, err_path, memory)
        status = None
        while time.monotonic() - start < time_cap:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                break
            time.sleep(0.005 if time.monotonic() - start < 1 else 0.05)
        else:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            outcome.problems.append("hangs")
        outcome.seconds = time.monotonic() - start
        # whatever the child's session left running (workers) goes with it
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(pid, signal.SIGKILL)
        outcome.stderr = Path(err_path).read_text(errors="replace")
    if status is not None and "hangs" not in outcome.problems:
        if os.WIFSIGNALED(status):
            outcome.problems.append("crashes")
            outcome.code = -os.WTERMSIG(status)
        else:
            outcome.code = os.WEXITSTATUS(status)
    lines = [ln for ln in outcome.stderr.splitlines() if ln.strip()]
    if "Traceback" in outcome.stderr or outcome.code in (97,):
        outcome.problems.append("tracebacks")
    elif outcome.code == 0 and 0 not in attempt.ok_codes:
        outcome.problems.append("silent accepts")
    elif outcome.code is not None and outcome.code not in attempt.ok_codes:
        outcome.problems.append("wrong exits")
    elif outcome.code == 2 and not attempt.call:
        errors = [ln for ln in lines if not ln.startswith(("subtask-opt: compiling",
                                                          "warning:"))]
        if len(errors) != 1:
            outcome.problems.append("wrong exits")
    for p in attempt.outputs:
        if Path(p).exists() and not Path(p).is_dir():
            outcome.problems.append("partial outputs")
    if fx.leftovers():
        outcome.problems.append("partial outputs")
        for p in fx.leftovers():
            with contextlib.suppress(OSError):
                Path(p).unlink()
    if fx.changed():
        outcome.problems.append("inputs changed")
        fx.snapshot()
    return outcome


def preload() -> None:
    """Import what attempts use, so that forked children start warm."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot  # noqa: F401

    import subtask_opt  # noqa: F401
    import subtask_opt.batch  # noqa: F401
    import subtask_opt.cli  # noqa: F401
    import subtask_opt.kinematics.serial  # noqa: F401
    import subtask_opt.planners.agv.scenarios  # noqa: F401
    import subtask_opt.planners.grid.world  # noqa: F401
    import subtask_opt.planners.polygon.world  # noqa: F401
    import subtask_opt.planners.reactive.scenarios  # noqa: F401
    import subtask_opt.tour.tsplib  # noqa: F401


@contextlib.contextmanager
def fixtures() -> Iterator[Fixtures]:
    with tempfile.TemporaryDirectory(prefix="campaign-") as tmp:
        fx = Fixtures(Path(tmp))
        try:
            yield fx
        finally:
            fx.close()


def warm(fx: Fixtures, *, progress: bool = False) -> None:
    """Run every command's base once, uncapped and uncounted: numba compiles (and caches)
    its kernels here, not inside a capped attempt."""
    for cmd in commands(fx):
        o = run_attempt(Attempt("warm-up", cmd.base, ok_codes=(0,)), fx, time_cap=900.0)
        if progress:
            print(f"  warm-up {cmd.name}: exit {o.code}, {o.seconds:.1f} s", file=sys.stderr,
                  flush=True)
        if o.code != 0:  # a base that fails would make every bad value look refused
            raise SystemExit(f"the base of {cmd.name!r} does not succeed (exit {o.code}): "
                             f"{' '.join(cmd.base)}\n{o.stderr}")


def run(attempts: list[Attempt], fx: Fixtures, *, time_cap: float = TIME_CAP_S,
        memory: int = MEMORY_CAP, progress: bool = False, warm_up: bool = True) -> list[Outcome]:
    preload()
    fx.snapshot()
    if warm_up:
        warm(fx, progress=progress)
        fx.snapshot()
    outcomes = []
    for i, a in enumerate(attempts):
        outcomes.append(run_attempt(a, fx, time_cap=time_cap, memory=memory))
        if progress and (i + 1) % 100 == 0:
            bad = sum(bool(o.problems) for o in outcomes)
            print(f"  {i + 1}/{len(attempts)} attempts, {bad} with problems", file=sys.stderr,
                  flush=True)
    return outcomes


def table(outcomes: list[Outcome]) -> str:
    rows: dict[str, Counter[str]] = defaultdict(Counter)
    for o in outcomes:
        family = o.attempt.call and "api" or " ".join(
            o.attempt.argv[:2] if o.attempt.argv[0] in ("plan", "bench") else o.attempt.argv[:1])
        rows[family]["attempts"] += 1
        for p in set(o.problems):
            rows[family][p] += 1
    total: Counter[str] = Counter()
    for c in rows.values():
        total.update(c)
    head = f"{'command':<20}{'attempts':>9}" + "".join(f"{c:>16}" for c in COLUMNS)
    lines = [head, "-" * len(head)]
    for name in sorted(rows):
        c = rows[name]
        lines.append(f"{name:<20}{c['attempts']:>9}" + "".join(f"{c[k]:>16}" for k in COLUMNS))
    lines.append("-" * len(head))
    lines.append(f"{'total':<20}{total['attempts']:>9}" + "".join(f"{total[k]:>16}"
                                                                for k in COLUMNS))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--attempts", type=int, default=3000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--time-cap", type=float, default=TIME_CAP_S)
    ap.add_argument("--memory", type=int, default=MEMORY_CAP, help="RLIMIT_AS in bytes")
    ap.add_argument("--only", default=None, help="run only attempts whose label has this")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    started = time.monotonic()
    with fixtures() as fx:
        attempts = generate(fx, args.attempts, args.seed)
        if args.only:  # comma-separated: attempts whose label or class has one of them
            words = args.only.split(",")
            attempts = [a for a in attempts if any(w in a.label or w in a.klass
                                                   for w in words)]
        outcomes = run(attempts, fx, time_cap=args.time_cap, memory=args.memory,
                       progress=True)
    print(table(outcomes))
    bad = [o for o in outcomes if o.problems]
    for o in bad[:60]:
        last = (o.stderr.strip().splitlines() or [""])[-1][:200]
        print(f"  {'/'.join(sorted(set(o.problems)))}: [{o.attempt.klass}] {o.attempt.label}"
              f" -> exit {o.code}: {last}")
    classes = Counter(o.attempt.klass for o in outcomes)
    print(f"{len(outcomes)} attempts in {len(classes)} classes, "
          f"{time.monotonic() - started:.0f} s; time cap {args.time_cap:g} s, "
          f"RLIMIT_AS {args.memory >> 20} MiB")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps({
            "attempts": len(outcomes), "classes": dict(classes),
            "problems": [{"class": o.attempt.klass, "label": o.attempt.label,
                          "problems": o.problems, "code": o.code,
                          "stderr": o.stderr[-2000:]} for o in bad]}, indent=1))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
