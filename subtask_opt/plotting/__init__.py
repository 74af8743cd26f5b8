"""Matplotlib figures, one module per family; nothing outside this package imports matplotlib."""
