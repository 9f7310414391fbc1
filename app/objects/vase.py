"""Vases (out-of-domain test category): open vessels with freer profiles, often without a handle.

The outer profile is a monotone cubic (PCHIP) through radii at five heights, so bellies, waists
and flared openings all occur.

| parameter      | range         | meaning                                                 |
|----------------|---------------|---------------------------------------------------------|
| height         | 0.120 - 0.250 | floor to rim                                            |
| base_radius    | 0.030 - 0.060 | radius at z = 0                                         |
| r1, r2, r3     | 0.025 - 0.085 | radii at 25 %, 50 %, 75 % of the height                 |
| rim_radius     | 0.020 - 0.065 | radius of the opening                                   |
| wall           | 0.003 - 0.006 | wall thickness                                          |
| bottom         | 0.006 - 0.012 | floor thickness                                         |
| handles        | 0, 1 or 2     | with probabilities 0.6, 0.25, 0.15 (2 = opposite sides) |
| handle_mid     | 0.55 - 0.75   | handle mid height, fraction of height                   |
| handle_span    | 0.20 - 0.40   | attachment spacing, fraction of height                  |
| handle_reach   | 0.025 - 0.045 | how far the handle bulges out                           |
| handle_radius  | 0.005 - 0.008 | tube radius                                             |
"""
from __future__ import annotations

import numpy as np
import trimesh
from scipy.interpolate import PchipInterpolator

from app.objects.handle import handle_path, hole_center
from app.objects.semantics import Semantics, sample_params
from app.objects.solids import hollow, to_trimesh, tube

RANGES = {
    "height": (0.120, 0.250),
    "base_radius": (0.030, 0.060),
    "r1": (0.025, 0.085),
    "r2": (0.025, 0.085),
    "r3": (0.025, 0.085),
    "rim_radius": (0.020, 0.065),
    "wall": (0.003, 0.006),
    "bottom": (0.006, 0.012),
    "handle_mid": (0.55, 0.75),
    "handle_span": (0.20, 0.40),
    "handle_reach": (0.025, 0.045),
    "handle_radius": (0.005, 0.008),
}
HANDLE_COUNTS, HANDLE_PROBS = (0, 1, 2), (0.6, 0.25, 0.15)


def build(seed: int, rng: np.random.Generator, family: str = "classic") -> tuple[trimesh.Trimesh, Semantics]:
    """One vase and its semantics (one family: `family` is accepted for the catalogue's sake)."""
    p = sample_params(RANGES, rng)
    p["handles"] = float(rng.choice(HANDLE_COUNTS, p=HANDLE_PROBS))
    H = p["height"]
    knots = np.array([0.0, 0.25, 0.5, 0.75, 1.0]) * H
    radius = PchipInterpolator(knots, [p["base_radius"], p["r1"], p["r2"], p["r3"], p["rim_radius"]])
    z = np.linspace(0.0, H, 60)
    r = radius(z)
    body, cavity = hollow(z, r, p["wall"], p["bottom"])

    handle_center = handle_axis = None
    if p["handles"] > 0:
        rh = p["handle_radius"]
        z_top = min(H * (p["handle_mid"] + p["handle_span"] / 2), H - rh - 0.004)
        z_bottom = H * (p["handle_mid"] - p["handle_span"] / 2)
        inset = p["wall"] / 2
        path = handle_path(float(radius(z_top)) - inset, float(radius(z_bottom)) - inset,
                           z_top, z_bottom, p["handle_reach"], 2.0)
        handle = tube(path, rh)
        if p["handles"] > 1:
            handle = handle + handle.rotate((0.0, 0.0, 180.0))
        body = (body + handle) - cavity
        mid = path[len(path) // 2]
        handle_center = hole_center(path, float(radius(mid[2])), rh)
        handle_axis = (0.0, 1.0, 0.0)

    sem = Semantics(category="vase", seed=seed, params=p, height=H, max_radius=float(r.max()),
                    rim_height=H, rim_radius=p["rim_radius"], rim_inner_radius=p["rim_radius"] - p["wall"],
                    handle_center=handle_center, handle_axis=handle_axis)
    return to_trimesh(body), sem
