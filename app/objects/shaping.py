"""Shape changes applied to a solid after it is built: non-round cross-sections and scan-like bumps.

Both are smooth maps of space applied to the solid's vertices (manifold3d's `warp_batch`), so a
watertight solid stays watertight; they are star-shaped about the z axis or small against the wall,
so it does not self-intersect.
"""
from __future__ import annotations

import numpy as np
from manifold3d import Manifold


def superellipse_radius(phi: np.ndarray, aspect: float, exponent: float) -> np.ndarray:
    """Radius along angle phi of the curve |x|^p + |y / aspect|^p = 1 (p = exponent; 2: an ellipse,
    larger: a rounded rectangle)."""
    c, s = np.abs(np.cos(phi)), np.abs(np.sin(phi)) / aspect
    return (c ** exponent + s ** exponent) ** (-1.0 / exponent)


def _smoothstep(t: np.ndarray) -> np.ndarray:
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def reshape_section(solid: Manifold, aspect: float, exponent: float, z_full: float, z_round: float) -> Manifold:
    """The solid of revolution with its horizontal sections turned into superellipses of `aspect`
    (y over x) and `exponent` up to z_full, blending back to round circles at z_round (> z_full):
    a round neck on an oval or flattened body. Radius along x is kept."""
    def warp(v: np.ndarray) -> np.ndarray:  # (N, 3) -> (N, 3)
        phi = np.arctan2(v[:, 1], v[:, 0])  # (N,)
        k = superellipse_radius(phi, aspect, exponent)  # (N,) <= 1 where aspect <= 1
        blend = 1.0 - _smoothstep((v[:, 2] - z_full) / (z_round - z_full))  # 1 on the body, 0 at the neck
        scale = 1.0 + (k - 1.0) * blend
        return np.column_stack([v[:, 0] * scale, v[:, 1] * scale, v[:, 2]])

    return solid.warp_batch(warp)


def bumps(solid: Manifold, amplitude: float, rng: np.random.Generator, waves: int = 6,
          wavelength: tuple[float, float] = (0.015, 0.04)) -> Manifold:
    """The solid displaced by a smooth random field of `waves` plane waves (amplitude in metres, each
    wave's length drawn from `wavelength`): the lumps and ripples of a scanned surface. Nearby points
    move alike, so a wall keeps its thickness."""
    directions = rng.normal(size=(waves, 3))  # (W, 3)
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    k = 2 * np.pi / rng.uniform(*wavelength, size=waves)  # (W,)
    phase = rng.uniform(0, 2 * np.pi, size=waves)  # (W,)
    push = rng.normal(size=(waves, 3))  # (W, 3) direction each wave moves points
    push *= amplitude / np.sqrt(waves) / np.linalg.norm(push, axis=1, keepdims=True)

    def warp(v: np.ndarray) -> np.ndarray:  # (N, 3) -> (N, 3)
        return v + np.sin(v @ (directions * k[:, None]).T + phase) @ push  # (N, W) @ (W, 3)

    return solid.warp_batch(warp)
