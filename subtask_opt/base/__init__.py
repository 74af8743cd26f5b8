"""What every family shares: errors, stopping criteria, result types, progress, geometry.

Depends on numpy and the standard library only.
"""
