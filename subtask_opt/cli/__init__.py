"""Command-line interface: ``subtask-opt solve | plan ... | bench ...``.

One module per command family; each parses its arguments, makes one library call
and prints. :func:`main` is the console-script entry point.
"""

from subtask_opt.cli.app import build_parser, main

__all__ = ["build_parser", "main"]
