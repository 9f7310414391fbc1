"""Bottles: a closed solid - body, shoulder, neck and a top - in the families of `app.objects.families`.

The classic family (seeds of the `train` and `test` splits) is today's bottle, bit for bit: a round
body, a cosine shoulder, a straight neck and a lip.

| parameter    | range         | meaning                                            |
|--------------|---------------|----------------------------------------------------|
| body_radius  | 0.030 - 0.045 | radius of the body                                 |
| body_height  | 0.090 - 0.160 | height of the straight body                        |
| bulge        | -0.004 - 0.004| extra body radius at its mid height                |
| shoulder     | 0.020 - 0.050 | height of the shoulder (body radius -> neck radius)|
| neck_radius  | 0.011 - 0.018 | radius of the neck                                 |
| neck_length  | 0.030 - 0.060 | length of the straight neck                        |
| lip          | 0.0015 - 0.003| radial size of the lip at the top                  |

The wide families draw more (`WIDE_RANGES`); where each range comes from is in
`docs/objects.md` (typical published product dimensions: 28 mm PCO neck finishes, 24/410 and
28/410 closures and pumps, 250-750 ml shampoo and detergent bottles). The body's half-width along
x is `body_radius` (up to 48 mm: a 96 mm wide bottle), along y `aspect` times that.

Bottles are closed (a capped bottle): the neck is grasped from outside, nothing goes in.
"""
from __future__ import annotations

import numpy as np
import trimesh
from manifold3d import Manifold

from app.objects.families import CLASSIC
from app.objects.handle import handle_path
from app.objects.semantics import Semantics, sample_params
from app.objects.shaping import reshape_section
from app.objects.solids import SEGMENTS, closed_profile, revolve, to_trimesh, tube

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
WIDE_RANGES = {
    "body_radius": (0.032, 0.048),   # half-width along x: 64-96 mm wide bodies
    "body_height": (0.090, 0.160),
    "shoulder": (0.015, 0.045),
    "neck_radius": (0.011, 0.016),   # 22-32 mm outside the thread (24 mm and 28 mm finishes)
    "neck_length": (0.012, 0.030),   # the neck left bare under the cap
    "cap_radius": (0.002, 0.006),    # how much wider than the neck a screw cap or a tapered cap is
    "cap_height": (0.014, 0.026),
    "cap_taper_deg": (10.0, 30.0),   # a tapered cap's side, from vertical: flip-top discs to conical spouts
    "handle_reach": (0.024, 0.034),
    "handle_radius": (0.008, 0.011),
}
SECTIONS = {  # family -> (aspect range, exponent range) of the body's cross-section
    "oval": ((0.55, 0.80), (2.0, 2.0)),
    "rounded-rect": ((0.50, 0.80), (3.5, 6.0)),
    "grip-handle": ((0.70, 1.00), (2.0, 2.0)),
    "tapered-cap": ((0.60, 1.00), (2.0, 4.0)),
    "flat-pump": ((0.35, 0.50), (2.5, 4.0)),
}
SHOULDERS = {  # shape of the shoulder: share s in [0, 1] from the body up to the neck -> share of the step left
    "cosine": lambda s: 0.5 * (1.0 + np.cos(np.pi * s)),
    "conical": lambda s: 1.0 - s,
    "domed": lambda s: np.sqrt(np.clip(1.0 - s ** 2, 0.0, 1.0)),
    "stepped": lambda s: (1.0 - s) ** 3,
}
PUMP = {"collar": 0.012, "stem_radius": 0.005, "stem": 0.022, "head": (0.048, 0.020, 0.017)}  # m; 28/410 pumps


def build(seed: int, rng: np.random.Generator, family: str = CLASSIC,
          fixed: dict[str, float] | None = None) -> tuple[trimesh.Trimesh, Semantics]:
    """One bottle of the family and its semantics; `fixed`: wide-family parameters set, not drawn."""
    return _classic(seed, rng) if family == CLASSIC else _wide(seed, rng, family, fixed or {})


def _classic(seed: int, rng: np.random.Generator) -> tuple[trimesh.Trimesh, Semantics]:
    p = sample_params(RANGES, rng)
    Rb, Rn, Hb = p["body_radius"], p["neck_radius"], p["body_height"]
    z_body = np.linspace(0.0, Hb, 24)
    r_body = Rb + p["bulge"] * np.sin(np.pi * z_body / Hb)
    s = np.linspace(0.0, 1.0, 20)[1:]
    z_sh = Hb + p["shoulder"] * s
    r_sh = Rn + (Rb - Rn) * SHOULDERS["cosine"](s)
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


def _wide(seed: int, rng: np.random.Generator, family: str, fixed: dict[str, float]) -> tuple[trimesh.Trimesh, Semantics]:
    p = {**sample_params(WIDE_RANGES, rng), **fixed}
    (a_lo, a_hi), (e_lo, e_hi) = SECTIONS[family]
    p["aspect"], p["exponent"] = float(rng.uniform(a_lo, a_hi)), float(rng.uniform(e_lo, e_hi))
    shoulder = str(rng.choice(sorted(SHOULDERS)))
    Rb, Rn, Hb = p["body_radius"], p["neck_radius"], p["body_height"]
    s = np.linspace(0.0, 1.0, 24)[1:]
    neck_lo = Hb + p["shoulder"]
    neck_hi = neck_lo + p["neck_length"]
    z = np.concatenate([np.linspace(0.0, Hb, 16), Hb + p["shoulder"] * s, [neck_hi]])
    r = np.concatenate([np.full(16, Rb), Rn + (Rb - Rn) * SHOULDERS[shoulder](s), [Rn]])
    body = reshape_section(revolve(closed_profile(z, r), 2 * SEGMENTS), p["aspect"], p["exponent"], Hb, neck_lo)
    if family == "grip-handle":
        body = body + _grip_handle(p, shoulder)
    top, cap = _top(family, p, neck_hi)
    solid = body + cap
    sem = Semantics(category="bottle", seed=seed, params={**p, "family": family, "shoulder_shape": shoulder},
                    height=top, max_radius=Rb, rim_height=top, rim_radius=Rn + p["cap_radius"],
                    neck_height=(neck_lo + neck_hi) / 2, neck_radius=Rn, neck_range=(neck_lo, neck_hi))
    return to_trimesh(solid), sem


def _top(family: str, p: dict, z0: float) -> tuple[float, Manifold]:
    """What closes the neck at height z0: (the bottle's top height, the solid)."""
    Rn, Rc, hc = p["neck_radius"], p["neck_radius"] + p["cap_radius"], p["cap_height"]
    overlap = 0.001  # sunk into the neck so the union is one solid
    if family == "flat-pump":
        collar = Manifold.cylinder(PUMP["collar"] + overlap, Rn + 0.003, Rn + 0.003, SEGMENTS).translate((0, 0, z0 - overlap))
        stem_z = z0 + PUMP["collar"]
        stem = Manifold.cylinder(PUMP["stem"] + overlap, PUMP["stem_radius"], PUMP["stem_radius"], 32)
        length, width, height = PUMP["head"]
        head = Manifold.cube((length, width, height)).translate((-0.012, -width / 2, stem_z + PUMP["stem"]))
        return stem_z + PUMP["stem"] + height, collar + stem.translate((0, 0, stem_z - overlap)) + head
    if family == "tapered-cap":
        r_top = Rc - hc * np.tan(np.radians(p["cap_taper_deg"]))
        z = np.array([0.0, hc - 0.003, hc - 0.001, hc])
        r = np.array([Rc, r_top + 0.0012, r_top - 0.001, r_top - 0.003])  # a rounded top edge
        return z0 + hc - overlap, revolve(closed_profile(z - overlap, r)).translate((0, 0, z0))
    z = np.array([0.0, hc - 0.0015, hc])  # a screw cap: straight, a small chamfer on top
    r = np.array([Rc, Rc, Rc - 0.0015])
    return z0 + hc - overlap, revolve(closed_profile(z - overlap, r)).translate((0, 0, z0))


def _grip_handle(p: dict, shoulder: str) -> Manifold:
    """A grip loop on the +x side from the upper shoulder down to the body's middle."""
    Rb, Rn, Hb, sh = p["body_radius"], p["neck_radius"], p["body_height"], p["shoulder"]
    z_top, z_bottom = Hb + 0.4 * sh, 0.45 * Hb
    x_top = Rn + (Rb - Rn) * SHOULDERS[shoulder](np.array(0.4))  # on the x axis the section keeps its radius
    inset = 0.004
    path = handle_path(float(x_top) - inset, Rb - inset, z_top, z_bottom, p["handle_reach"], 3.0)
    return tube(path, p["handle_radius"])
