"""CLI commands for the polygon planners (registered by :func:`register`)."""

from __future__ import annotations

import argparse


def register(plan: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``plan polygon`` and its benchmarks (not built yet)."""
