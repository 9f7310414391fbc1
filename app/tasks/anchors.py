"""Anchor meshes for templates: the gripper (in its TCP frame), the rack and the shelf (fixture frames)."""
from __future__ import annotations

import trimesh
from manifold3d import Manifold

from app.objects import fixture
from app.objects.solids import to_trimesh
from hardware.gripper_geometry import GripperGeometry

ANCHORS = ("gripper", "rack", "shelf")


def gripper_mesh(opening: float | None = None, geometry: GripperGeometry = GripperGeometry()) -> trimesh.Trimesh:
    """Palm and two fingers as boxes in the TCP frame (z = approach, fingers open along y).

    `opening` is the distance between the finger pads (default: fully open, the stroke).
    One solid (a manifold3d union): boxes that merely touch, concatenated, share coplanar faces
    that make ray-parity inside tests miscount (measured: cloud points "inside" by 39 mm).
    """
    opening = geometry.stroke if opening is None else opening
    px, py, pz = geometry.palm
    fx, fy, fz = geometry.finger
    z0 = -geometry.tcp_z  # tool0 in the TCP frame
    solid = Manifold.cube((px, py, pz), center=True).translate((0.0, 0.0, z0 + pz / 2))
    for sign in (1, -1):
        centre = (0.0, sign * (opening / 2 + fy / 2), z0 + pz + fz / 2 - 0.001)  # 1 mm into the palm
        solid += Manifold.cube((fx, fy, fz + 0.002), center=True).translate(centre)
    return to_trimesh(solid)


def anchor_mesh(name: str) -> trimesh.Trimesh:
    """The mesh of an anchor by name, in the frame its template poses refer to."""
    if name not in ANCHORS:
        raise ValueError(f"unknown anchor {name!r}; choose one of {', '.join(ANCHORS)}")
    if name == "gripper":
        return gripper_mesh()
    return fixture(name).mesh

