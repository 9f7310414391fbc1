"""Bottles: a closed solid of revolution - body, a smooth shoulder, a straight neck and a lip.

| parameter    | range         | meaning                                            |
|--------------|---------------|----------------------------------------------------|
| body_radius  | 0.030 - 0.045 | radius of the body                                 |
| body_height  | 0.090 - 0.160 | height of the straight body                        |
| bulge        | -0.004 - 0.004| extra body radius at its mid height                |
| shoulder     | 0.020 - 0.050 | height of the shoulder (body radius -> neck radius)|
| neck_radius  | 0.011 - 0.018 | radius of the neck                                 |
| neck_length  | 0.030 - 0.060 | length of the straight neck                        |
| lip          | 0.0015 - 0.003| radial size of the lip at the top                  |

Bottles are closed (a capped bottle): the neck is grasped from outside, nothing goes in.
"""
from __future__ import annotations

import numpy as np
import trimesh

from app.objects.semantics import Semantics, sample_params
from app.objects.solids import closed_profile, revolve, to_trimesh

RANGES = {
    "body_radius": (0.030, 0.045),
    "body_height": (0.090, 0.160),
    "bulge": (-0.004, 0.004),
    "shoulder": (0.020, 0.050),
    "neck_radius": (0.011, 0.018),
    "neck_length": (0.030, 0.060),
    "lip": (0.0015, 0.003),
}
LIP_HEIGHT = 0.006


def build(seed: int, rng: np.random.Generator) -> tuple[trimesh.Trimesh, Semantics]:
    """One bottle and its semantics."""
    p = sample_params(RANGES, rng)
    Rb, Rn, Hb = p["body_radius"], p["neck_radius"], p["body_height"]
    z_body = np.linspace(0.0, Hb, 24)
    r_body = Rb + p["bulge"] * np.sin(np.pi * z_body / Hb)
    s = np.linspace(0.0, 1.0, 20)[1:]
    z_sh = Hb + p["shoulder"] * s
    r_sh = Rn + (Rb - Rn) * 0.5 * (1.0 + np.cos(np.pi * s))  # smooth cosine blend
    neck_lo = Hb + p["shoulder"]
    neck_hi = neck_lo + p["neck_length"]
    top = neck_hi + LIP_HEIGHT
    z_neck = np.array([neck_hi, neck_hi + 0.001, top - 0.001, top])
    r_neck = np.array([Rn, Rn + p["lip"], Rn + p["lip"], Rn + p["lip"] * 0.5])
    z = np.concatenate([z_body, z_sh, z_neck])
    r = np.concatenate([r_body, r_sh, r_neck])
    solid = revolve(closed_profile(z, r))
    sem = Semantics(category="bottle", seed=seed, params=p, height=top,
                    max_radius=float(r.max()), rim_height=top, rim_radius=Rn + p["lip"],
                    neck_height=(neck_lo + neck_hi) / 2, neck_radius=Rn, neck_range=(neck_lo, neck_hi))
    return to_trimesh(solid), sem
