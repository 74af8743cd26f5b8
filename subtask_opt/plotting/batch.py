"""Figure of a batch of sequencing jobs: each job's total time, failed jobs marked."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt


def batch_figure(results: list[Any], *, title: str = "") -> Any:
    """Horizontal bars of the jobs' total times (s), failed jobs as red marks, in job order."""
    n = len(results)
    height = min(max(2.5, 0.22 * n + 1.2), 14.0)
    fig, ax = plt.subplots(figsize=(8.0, height), constrained_layout=True)
    rows = range(n)
    times = [r.total_time if r.success and r.total_time is not None else 0.0 for r in results]
    ax.barh(list(rows), times, color="tab:blue", label="solved: total time of the tour")
    failed = [i for i, r in enumerate(results) if not r.success]
    if failed:
        ax.scatter([0.0] * len(failed), failed, marker="x", color="tab:red", zorder=3,
                   label=f"failed ({len(failed)}; errors in the JSON)")
    if n <= 60:
        ax.set_yticks(list(rows), [str(r.id) for r in results], fontsize=7)
    else:
        ax.set_ylabel("job (in input order)")
    ax.invert_yaxis()
    ax.set_xlabel("total time of the tour [s]")
    ax.set_title(title or f"batch of {n} sequencing jobs")
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(axis="x", alpha=0.3)
    return fig


def save_batch_figure(results: list[Any], path: str | Path, *, title: str = "") -> None:
    """Write :func:`batch_figure` to ``path``."""
    fig = batch_figure(results, title=title)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
