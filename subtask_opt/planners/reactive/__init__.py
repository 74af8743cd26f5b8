"""Reactive navigation with a sonar ring: fuzzy via-point selection, VFF, VFH."""
