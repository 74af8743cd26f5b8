"""Reproductions of the five source papers: :func:`reproduce` runs one paper's experiments.

Each paper module (``p000_grid`` ... ``p004_agv``) has
``run(out, *, quick, seed, map_runs) -> (rows, figure paths)``; it runs that paper's
experiments with its parameters on the library's planners and solvers,
writes its figures, and returns one :class:`~subtask_opt.papers.report.Row`
per numbered result of the paper: the paper's value, ours and the deviation
(``subtask-opt reproduce 000|001|002|003|004 [--out DIR]``, ``make papers``).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from subtask_opt.base.errors import ParameterError
from subtask_opt.papers.report import PaperReport, Row

PAPERS: dict[str, str] = {
    "000": "subtask_opt.papers.p000_grid",
    "001": "subtask_opt.papers.p001_reactive",
    "002": "subtask_opt.papers.p002_sequencing",
    "003": "subtask_opt.papers.p003_maklink",
    "004": "subtask_opt.papers.p004_agv",
}
"""Paper id -> the module that reproduces it."""


def reproduce(paper: str, out: str | Path, *, quick: bool = False, seed: int = 0,
              map_runs: Any = None) -> PaperReport:
    """Run paper ``paper``'s experiments; figures and ``table_<paper>.{txt,md,json}`` into ``out``.

    Args:
        paper: ``"000"`` ... ``"004"`` (the seed papers' numbers).
        out: folder for the figures and tables (created if needed).
        quick: fewer seeds and runs (for the tests); the paper's parameters otherwise.
        seed: first seed of every stochastic experiment.
        map_runs: how suites run their independent runs (paper 004's suite), e.g.
            :func:`subtask_opt.batch.suite_mapper`; default: one after another here.

    Raises:
        ParameterError: an unknown paper id (the message lists the ids).
    """
    import importlib

    if paper not in PAPERS:
        raise ParameterError(f"paper must be one of {', '.join(PAPERS)}, got {paper!r}")
    from subtask_opt.base.errors import require_int

    require_int("reproduce", "seed", seed, 0, 2**63 - 1000)
    module = importlib.import_module(PAPERS[paper])
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    rows, files = module.run(folder, quick=quick, seed=seed, map_runs=map_runs)
    report = PaperReport(paper, module.TITLE, tuple(rows),
                         files=tuple(str(f) for f in files), quick=quick,
                         seconds=time.perf_counter() - start)
    report.write(folder)
    return report


__all__ = ["PAPERS", "PaperReport", "Row", "reproduce"]
