"""The arm product: one robot, targets, leg-time models, the problem compiled into a tour,
trajectories and reports. Kinematics live in :mod:`subtask_opt.kinematics`, the cell's
geometry in :mod:`subtask_opt.cell`.

The public names are re-exported by :mod:`subtask_opt`.
"""
