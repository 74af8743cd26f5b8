"""The arm product: robot model, subtasks, time models, sequencing, trajectories, exact oracles.

The public names are re-exported by :mod:`subtask_opt`.
"""
