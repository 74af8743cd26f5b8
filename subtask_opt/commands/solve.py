"""``subtask-opt solve``: order the subtasks of a planar arm for minimum time."""

from __future__ import annotations

import argparse


def register(root: argparse._SubParsersAction) -> None:
    """Add ``solve`` (not built yet)."""
