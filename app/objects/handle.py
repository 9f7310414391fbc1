"""A C-shaped handle (mug, vase): a round tube on a superellipse arc in the x-z plane."""
from __future__ import annotations

import numpy as np


def handle_path(x_top: float, x_bottom: float, z_top: float, z_bottom: float, reach: float,
                squareness: float, n: int = 25) -> np.ndarray:
    """Centre line of the handle tube, (n, 3), in the y = 0 plane on the +x side.

    The arc runs from (x_top, z_top) to (x_bottom, z_bottom) - both just inside the vessel wall -
    bulging out by `reach` along +x; `squareness` is the superellipse exponent (2 = ellipse,
    larger = boxier).
    """
    theta = np.linspace(np.pi / 2, -np.pi / 2, n)
    c, s = np.cos(theta), np.sin(theta)
    e = 2.0 / squareness
    u = (z_top - z_bottom) / 2.0
    x_base = x_bottom + (x_top - x_bottom) * (s + 1.0) / 2.0  # wall attachment, blended along z
    x = x_base + reach * np.abs(c) ** e
    z = (z_top + z_bottom) / 2.0 + u * np.sign(s) * np.abs(s) ** e
    return np.stack([x, np.zeros(n), z], axis=1)


def hole_center(path: np.ndarray, wall_radius_mid: float, tube_radius: float) -> tuple[float, float, float]:
    """Centre of the opening between the wall (at the handle's mid height) and the tube's inner edge."""
    mid = path[len(path) // 2]
    inner_edge = mid[0] - tube_radius
    return ((wall_radius_mid + inner_edge) / 2.0, 0.0, float(mid[2]))
