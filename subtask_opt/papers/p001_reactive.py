"""Seed paper 001 (fuzzy via-point navigation): Table 1 and the three scenarios (Figs. 7-9).

Table 1 is recomputed from its printed memberships (eq. 7, the plain minimum).
The scenarios' geometry is not printed; the project's built-in scenarios
(``simple``, ``u-trap``, ``corridor``) rebuild them, so only their outcomes
(reached the goal, or stuck in the trap without the escape) are compared.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from subtask_opt.papers.report import Row

TITLE = "fuzzy via-point selection with a sonar ring (reactive navigation)"

#: Figs. 7-9: what the paper shows for each scenario and navigator.
SCENARIOS = (
    ("Fig. 7", "simple", "fuzzy", "success"),
    ("Fig. 8", "u-trap", "fuzzy-no-escape", "fails (local minimum)"),
    ("Fig. 8", "u-trap", "fuzzy", "success"),
    ("Fig. 9", "corridor", "fuzzy", "success"),
)


def run(out: Path, *, quick: bool = False, seed: int = 0,
        map_runs: Any = None) -> tuple[list[Row], list[Path]]:
    """Table 1 and the scenarios' outcomes; figures into ``out``."""
    from subtask_opt.planners.reactive.fuzzy import table1
    from subtask_opt.planners.reactive.scenarios import paper_scenario
    from subtask_opt.planners.reactive.simulation import simulate
    from subtask_opt.plotting.reactive import save_run_figure, save_table1_figure

    report = table1()
    rows = [Row(f"Table 1: muD of candidate {i + 1}", float(p), float(o), "",
                "eq. 7, min of the printed muG1..muG3")
            for i, (p, o) in enumerate(zip(report.paper_mu_d, report.mu_d, strict=True))]
    rows.append(Row("Table 1: chosen candidate", report.paper_choice, report.choice))
    files = [save_table1_figure(report, out / "001_table1.png")]
    for fig, name, navigator, paper in SCENARIOS:
        sc = paper_scenario(name)
        r = simulate(sc.world, sc.start, sc.goal, navigator, seed=seed)
        ours = "success" if r.success else f"fails ({r.outcome.value})"
        if paper.startswith("fails") and not r.success:
            ours = paper if r.outcome.value in ("stall", "timeout") else ours
        rows.append(Row(f"{fig}: {name}, {navigator}", paper, ours, "",
                        f"rebuilt scenario; path {r.path_length:.2f}, {r.steps} steps"))
        files.append(save_run_figure(sc.world, r, out / f"001_{name}_{navigator}.png"))
    return rows, files
