"""A generated wing-skin-like panel of drilling targets (seeded), for scale benchmarks.

A doubly curved panel in front of the robot base: a cylinder of radius ``radius`` about
the vertical axis through ``(x0 - radius, 0)`` with a slight parabolic bulge in z,
``width`` x ``height`` metres, its holes on a jittered grid (rows along y, a seeded
choice of ``n`` grid cells, each moved by up to 20% of the pitch); the tool axis at
every hole is the panel's normal pointing away from the base (drilling into the skin).
The defaults sit inside a UR10's reach (about 0.85-0.95 m from its base).
"""

from __future__ import annotations

import math

import numpy as np

from subtask_opt.base.errors import require_in_range, require_int


def wing_panel(n: int, *, seed: int = 0, width: float = 0.9, height: float = 0.6,
               radius: float = 1.5, x0: float = 0.85, z0: float = -0.05) -> np.ndarray:
    """(n, 6) rows ``x, y, z, dx, dy, dz`` (metres, unit axis) of the panel's holes."""
    require_int("wing_panel", "n", n, 1, 10_000_000)
    require_int("wing_panel", "seed", seed, 0)
    for name, value in (("width", width), ("height", height)):
        require_in_range("wing_panel", name, value, 1e-3, 100.0)
    require_in_range("wing_panel", "radius", radius, width, 1e4)
    rng = np.random.default_rng(seed)
    rows = max(1, round(math.sqrt(n * height / width)))
    cols = math.ceil(n / rows)
    u = (np.arange(cols) + 0.5) / cols
    v = (np.arange(rows) + 0.5) / rows
    uu, vv = (a.ravel() for a in np.meshgrid(u, v))
    pick = np.sort(rng.choice(uu.size, n, replace=False))
    uu = uu[pick] + rng.uniform(-0.2, 0.2, n) / cols
    vv = vv[pick] + rng.uniform(-0.2, 0.2, n) / rows
    y = (uu - 0.5) * width
    z = z0 + vv * height
    cx = x0 - radius
    x = cx + np.sqrt(radius ** 2 - y ** 2) + 0.05 * (vv - 0.5) ** 2
    normal = np.stack([x - cx, y, np.zeros(n)], axis=1)
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    return np.column_stack([x, y, z, normal])


__all__ = ["wing_panel"]
