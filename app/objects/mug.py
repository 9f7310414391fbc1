"""Mugs: a tapered, slightly bulged cup of revolution with a wall, a floor and a C-shaped handle.

Parameter ranges (metres unless noted), chosen to span ordinary coffee and tea mugs:

| parameter         | range          | meaning                                                     |
|-------------------|----------------|-------------------------------------------------------------|
| height            | 0.080 - 0.120  | floor to rim                                                |
| radius            | 0.035 - 0.050  | outer radius at the bottom                                  |
| taper             | -0.12 - 0.18   | rim radius = radius * (1 + taper)                           |
| bulge             | 0.000 - 0.006  | extra radius at mid height (profile curvature)              |
| wall              | 0.003 - 0.006  | wall thickness (normal to the surface)                      |
| bottom            | 0.006 - 0.010  | floor thickness                                             |
| handle_mid        | 0.42 - 0.58    | handle mid height, fraction of height                       |
| handle_span       | 0.45 - 0.70    | handle attachment spacing, fraction of height               |
| handle_reach      | 0.028 - 0.042  | how far the handle's centre line bulges out from the wall   |
| handle_radius     | 0.005 - 0.008  | tube radius                                                 |
| handle_squareness | 2.0 - 4.0      | superellipse exponent of the handle arc (2 = elliptic)      |

The handle's hole is at least ~2 cm wide, so a rack peg of 6 mm radius fits through it.

That is the classic family (seeds of the `train` and `test` splits), bit for bit. The wide families
(`app.objects.families`) change what `FAMILY_RANGES` lists after drawing the above; where each range
comes from is in `docs/objects.md`.
"""
from __future__ import annotations

import numpy as np
import trimesh

from app.objects.families import CLASSIC
from app.objects.handle import handle_path, hole_center
from app.objects.semantics import Semantics, sample_params
from app.objects.shaping import bumps
from app.objects.solids import hollow, to_trimesh, tube

RANGES = {
    "height": (0.080, 0.120),
    "radius": (0.035, 0.050),
    "taper": (-0.12, 0.18),
    "bulge": (0.000, 0.006),
    "wall": (0.003, 0.006),
    "bottom": (0.006, 0.010),
    "handle_mid": (0.42, 0.58),
    "handle_span": (0.45, 0.70),
    "handle_reach": (0.028, 0.042),
    "handle_radius": (0.005, 0.008),
    "handle_squareness": (2.0, 4.0),
}
FAMILY_RANGES = {  # family -> the parameters it draws anew (clear_hole: the handle hole's clear width, m)
    "small-hole": {"clear_hole": (0.018, 0.022)},
    "large-hole": {"handle_reach": (0.042, 0.055), "handle_span": (0.60, 0.78), "handle_mid": (0.36, 0.64)},
    "flat-handle": {"strap_width": (2.0, 2.8), "strap_thickness": (0.55, 0.75)},  # times handle_radius
    "flared-bumpy": {"taper": (0.20, 0.40), "handle_radius": (0.009, 0.012), "bumps": (0.0004, 0.0009)},
}


def _family_params(p: dict[str, float], family: str, rng: np.random.Generator) -> dict[str, float]:
    """The classic draw p with the family's own parameters drawn over it."""
    if family == CLASSIC:
        return p
    p = {**p, **sample_params(FAMILY_RANGES[family], rng)}
    if "clear_hole" in p:  # clear width = reach - tube radius - half the wall (the tube starts inside the wall)
        p["handle_reach"] = p["clear_hole"] + p["handle_radius"] + p["wall"] / 2
    return p


def outer_radius(p: dict[str, float], z: np.ndarray) -> np.ndarray:
    """Outer radius of the body at heights z."""
    s = z / p["height"]
    return p["radius"] * (1.0 + p["taper"] * s) + p["bulge"] * np.sin(np.pi * s)


def build(seed: int, rng: np.random.Generator, family: str = CLASSIC) -> tuple[trimesh.Trimesh, Semantics]:
    """One mug of the family and its semantics."""
    p = _family_params(sample_params(RANGES, rng), family, rng)
    H, rh = p["height"], p["handle_radius"]
    squash = (p.get("strap_thickness", 1.0), p.get("strap_width", 1.0), p.get("strap_thickness", 1.0))
    z = np.linspace(0.0, H, 40)
    r = outer_radius(p, z)
    body, cavity = hollow(z, r, p["wall"], p["bottom"])

    margin = rh + 0.004  # keep the tube clear of the rim and the table
    z_top = min(H * (p["handle_mid"] + p["handle_span"] / 2), H - margin)
    z_bottom = max(H * (p["handle_mid"] - p["handle_span"] / 2), margin)
    r_top, r_bottom = outer_radius(p, np.array([z_top, z_bottom]))
    inset = p["wall"] / 2  # attach inside the wall so the union is solid
    path = handle_path(r_top - inset, r_bottom - inset, z_top, z_bottom, p["handle_reach"], p["handle_squareness"])
    mug = (body + tube(path, rh, squash=squash)) - cavity
    if "bumps" in p:
        mug = bumps(mug, p["bumps"], rng)
        mug = mug.translate((0.0, 0.0, -mug.bounding_box()[2]))  # back on z = 0
        H = mug.bounding_box()[5]  # the rim moved with the bumps

    z_mid = float(path[len(path) // 2, 2])
    rim_radius = float(outer_radius(p, np.array([H]))[0])
    sem = Semantics(
        category="mug", seed=seed, params={**p, "family": family} if family != CLASSIC else p, height=H,
        max_radius=float(r.max()), rim_height=H, rim_radius=rim_radius,
        rim_inner_radius=rim_radius - p["wall"],
        handle_center=hole_center(path, float(outer_radius(p, np.array([z_mid]))[0]), rh * squash[0]),
        handle_axis=(0.0, 1.0, 0.0),
    )
    return to_trimesh(mug), sem
