"""Bowls: an open vessel of revolution whose profile rises from a foot to a wide rim.

Outer radius r(z) = foot + (rim - foot) * (1 - (1 - z / height) ** roundness).

| parameter   | range         | meaning                                               |
|-------------|---------------|-------------------------------------------------------|
| rim_radius  | 0.060 - 0.090 | outer radius at the rim                               |
| height      | 0.040 - 0.075 | foot to rim                                           |
| foot        | 0.35 - 0.60   | foot radius as a fraction of the rim radius           |
| roundness   | 1.3 - 3.0     | profile exponent (1 = conical, larger = rounder side) |
| wall        | 0.003 - 0.006 | wall thickness (normal to the surface)                |
| bottom      | 0.006 - 0.010 | floor thickness                                       |
"""
from __future__ import annotations

import numpy as np
import trimesh

from app.objects.semantics import Semantics, sample_params
from app.objects.solids import hollow, to_trimesh

RANGES = {
    "rim_radius": (0.060, 0.090),
    "height": (0.040, 0.075),
    "foot": (0.35, 0.60),
    "roundness": (1.3, 3.0),
    "wall": (0.003, 0.006),
    "bottom": (0.006, 0.010),
}


def build(seed: int, rng: np.random.Generator) -> tuple[trimesh.Trimesh, Semantics]:
    """One bowl and its semantics."""
    p = sample_params(RANGES, rng)
    H, R = p["height"], p["rim_radius"]
    foot = p["foot"] * R
    z = np.linspace(0.0, H, 40)
    r = foot + (R - foot) * (1.0 - (1.0 - z / H) ** p["roundness"])
    body, _ = hollow(z, r, p["wall"], p["bottom"])
    sem = Semantics(category="bowl", seed=seed, params=p, height=H, max_radius=R,
                    rim_height=H, rim_radius=R, rim_inner_radius=R - p["wall"])
    return to_trimesh(body), sem
