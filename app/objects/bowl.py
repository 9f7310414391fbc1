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

That is the classic family (seeds of the `train` and `test` splits), bit for bit. The wide families
(`app.objects.families`) draw `FAMILY_RANGES` after it: a foot ring under the bowl, or a rim that
flares out, and heights from shallow to deep; where each range comes from is in `docs/objects.md`.
"""
from __future__ import annotations

import numpy as np
import trimesh

from app.objects.families import CLASSIC
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
FAMILY_RANGES = {
    "footed": {"height": (0.035, 0.095), "ring": (0.006, 0.012), "ring_step": (0.003, 0.006)},
    "flared-rim": {"height": (0.030, 0.095), "flare": (0.006, 0.014), "flare_share": (0.15, 0.30)},
}


def build(seed: int, rng: np.random.Generator, family: str = CLASSIC) -> tuple[trimesh.Trimesh, Semantics]:
    """One bowl of the family and its semantics."""
    p = sample_params(RANGES, rng)
    if family != CLASSIC:
        p = {**p, **sample_params(FAMILY_RANGES[family], rng), "family": family}
    H, R = p["height"], p["rim_radius"]
    foot = p["foot"] * R
    z = np.linspace(0.0, H, 40)
    r = foot + (R - foot) * (1.0 - (1.0 - z / H) ** p["roundness"])
    if "flare" in p:  # the top share of the wall bends outwards; the rim radius stays R
        start = H * (1.0 - p["flare_share"])
        r = r - p["flare"] + p["flare"] * np.clip((z - start) / (H - start), 0.0, 1.0) ** 2
    if "ring" in p:  # a foot ring of height `ring`, the bowl above it set in by `ring_step`
        z = np.concatenate([[0.0, p["ring"]], p["ring"] + 0.001 + z * (H - p["ring"] - 0.001) / H])
        r = np.concatenate([[foot, foot], r - p["ring_step"] * (1.0 - z[2:] / H) ** 2])
        p["bottom"] = max(p["bottom"], p["ring"] + 0.004)
    body, _ = hollow(z, r, p["wall"], p["bottom"])
    sem = Semantics(category="bowl", seed=seed, params=p, height=H, max_radius=float(r.max()),
                    rim_height=H, rim_radius=float(r[-1]), rim_inner_radius=float(r[-1]) - p["wall"])
    return to_trimesh(body), sem
