"""A paper reproduction: one :class:`Row` per numbered result, in a :class:`PaperReport`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from subtask_opt.base.errors import ParameterError

Value = float | int | str | None


def _check_value(owner: str, name: str, value: Any) -> None:
    if value is None or isinstance(value, str):
        return
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{owner}.{name} must be a number, a string or None, got {value!r}")
    if not math.isfinite(value):
        raise ParameterError(f"{owner}.{name} must be finite, got {value!r}")


@dataclass(frozen=True)
class Row:
    """One numbered result of a paper beside ours.

    Attributes:
        item: where the paper prints it ("Table 1, Dijkstra length").
        paper: the paper's value (a number, or words for a qualitative result).
        ours: our value (None: not reproduced, see ``note``).
        unit: the unit of both values ("" when none).
        note: how ours was obtained, or why it cannot match.
    """

    item: str
    paper: Value
    ours: Value
    unit: str = ""
    note: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.item, str) or not self.item.strip():
            raise ParameterError(f"Row.item must be a non-empty string, got {self.item!r}")
        _check_value("Row", "paper", self.paper)
        _check_value("Row", "ours", self.ours)

    @property
    def numeric(self) -> bool:
        """Whether both values are numbers (then :attr:`deviation` is relative)."""
        return all(isinstance(v, (int, float)) for v in (self.paper, self.ours))

    @property
    def deviation(self) -> str:
        """``+0.03%`` for numbers (``+2`` when the paper's value is 0), ``same`` /
        ``differs`` for words, ``-`` when either value is missing."""
        if self.ours is None or self.paper is None:
            return "-"
        if self.numeric:
            p, o = float(self.paper), float(self.ours)  # type: ignore[arg-type]
            if p == 0:
                return f"{o - p:+.4g}"
            return f"{100 * (o - p) / abs(p):+.2f}%"
        return "same" if str(self.paper) == str(self.ours) else "differs"

    def to_dict(self) -> dict[str, Any]:
        return {"item": self.item, "paper": self.paper, "ours": self.ours, "unit": self.unit,
                "deviation": self.deviation, "note": self.note}


def _cell(value: Value) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.7g}"
    return str(value)


@dataclass(frozen=True)
class PaperReport:
    """One paper's reproduction: its rows, the files written and how it was run."""

    paper: str
    title: str
    rows: tuple[Row, ...]
    files: tuple[str, ...] = ()
    quick: bool = False
    seconds: float = 0.0
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        if not self.rows:
            raise ParameterError(f"PaperReport {self.paper}: needs at least one row")

    def table(self) -> str:
        """The rows as a fixed-width text table (what ``subtask-opt reproduce`` prints)."""
        head = ("item", "paper", "ours", "deviation", "note")
        cells = [(r.item, _cell(r.paper) + (f" {r.unit}" if r.unit and r.paper is not None
                                             and not isinstance(r.paper, str) else ""),
                  _cell(r.ours) + (f" {r.unit}" if r.unit and r.ours is not None
                                   and not isinstance(r.ours, str) else ""),
                  r.deviation, r.note) for r in self.rows]
        widths = [max(len(head[k]), *(len(c[k]) for c in cells)) for k in range(4)]
        lines = ["  ".join(h.ljust(w) for h, w in zip(head[:4], widths, strict=True)) + "  note",
                 "-" * (sum(widths) + 8 + 6)]
        lines += ["  ".join(c[k].ljust(widths[k]) for k in range(4)) + "  " + c[4]
                  for c in cells]
        return "\n".join(line.rstrip() for line in lines)

    def markdown(self) -> str:
        """The rows as a Markdown table (the README's)."""
        out = ["| item | paper | ours | deviation | note |", "|---|---|---|---|---|"]
        for r in self.rows:
            unit = f" {r.unit}" if r.unit else ""
            paper = _cell(r.paper) + (unit if isinstance(r.paper, (int, float)) else "")
            ours = _cell(r.ours) + (unit if isinstance(r.ours, (int, float)) else "")
            cells = (r.item, paper, ours, r.deviation, r.note)
            out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
        return "\n".join(out)

    def to_dict(self) -> dict[str, Any]:
        return {"paper": self.paper, "title": self.title, "quick": self.quick,
                "seconds": self.seconds, "files": list(self.files), "notes": list(self.notes),
                "rows": [r.to_dict() for r in self.rows]}

    def write(self, out: Path) -> list[Path]:
        """Write ``table_<paper>.txt``, ``.md`` and ``.json`` into ``out``; their paths."""
        import json

        out.mkdir(parents=True, exist_ok=True)
        written = []
        for suffix, text in (("txt", self.table()), ("md", self.markdown()),
                             ("json", json.dumps(self.to_dict(), indent=1))):
            path = out / f"table_{self.paper}.{suffix}"
            path.write_text(text + "\n")
            written.append(path)
        return written


__all__ = ["PaperReport", "Row", "Value"]
