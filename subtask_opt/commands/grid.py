"""CLI commands for the grid planners (registered by :func:`register`)."""

from __future__ import annotations

import argparse


def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``plan grid`` and its benchmarks (not built yet)."""
