"""How much room a hung mug's handle leaves around the rack's peg: on its mesh, and in Bullet.

Bullet grows every convex hull by its collision margin, so the simulated hole is narrower than the
mesh's by about twice the margin (`SimWorldConfig.mesh_margin`; docs/cell.md). These two figures
say whether the simulated contact geometry is the object's own.
"""
from __future__ import annotations

import numpy as np
import trimesh

from app.objects import rack
from hardware.bullet import p
from hardware.se3 import invert, transform_points

HOLE_SPAN = (0.03, 0.09)  # m along the peg from its root: where a hung handle's hole can sit


def mesh_gap(mesh: trimesh.Trimesh, T_rack_obj: np.ndarray) -> float:
    """m between the peg's surface and the mesh (hung at T_rack_obj): the least distance from the
    peg's axis (over HOLE_SPAN) to the mesh, less the peg's radius."""
    lm = rack().landmarks
    u = np.linspace(*HOLE_SPAN, 25)[:, None]  # (25, 1)
    axis = np.asarray(lm["peg_origin"]) + u * np.asarray(lm["peg_direction"])  # (25, 3) rack frame
    inside = trimesh.proximity.signed_distance(mesh, transform_points(invert(T_rack_obj), axis))  # + inside
    return float(-inside.max()) - float(lm["peg_radius"])


def bullet_gap(client: int, body: int, rack_body: int, reach: float = 0.05) -> float:
    """m between two bodies as Bullet's narrow phase sees them, margins included (negative: overlap)."""
    p.performCollisionDetection(physicsClientId=client)
    points = p.getClosestPoints(body, rack_body, reach, physicsClientId=client)
    return min((c[8] for c in points), default=reach)
