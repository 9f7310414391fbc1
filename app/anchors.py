"""Anchor meshes for templates: the gripper (in its TCP frame), the rack and the shelf (fixture frames)."""
from __future__ import annotations

import trimesh

from app.objects import fixture
from hardware.sim.gripper_model import GripperGeometry

ANCHORS = ("gripper", "rack", "shelf")


def gripper_mesh(opening: float | None = None, geometry: GripperGeometry = GripperGeometry()) -> trimesh.Trimesh:
    """Palm and two fingers as boxes in the TCP frame (z = approach, fingers open along y).

    `opening` is the distance between the finger pads (default: fully open, the stroke).
    """
    opening = geometry.stroke if opening is None else opening
    px, py, pz = geometry.palm
    fx, fy, fz = geometry.finger
    z0 = -geometry.tcp_z  # tool0 in the TCP frame
    parts = [trimesh.creation.box((px, py, pz), trimesh.transformations.translation_matrix((0, 0, z0 + pz / 2)))]
    for sign in (1, -1):
        centre = (0.0, sign * (opening / 2 + fy / 2), z0 + pz + fz / 2)
        parts.append(trimesh.creation.box((fx, fy, fz), trimesh.transformations.translation_matrix(centre)))
    return trimesh.util.concatenate(parts)


def anchor_mesh(name: str) -> trimesh.Trimesh:
    """The mesh of an anchor by name, in the frame its template poses refer to."""
    if name not in ANCHORS:
        raise ValueError(f"unknown anchor {name!r}; choose one of {', '.join(ANCHORS)}")
    if name == "gripper":
        return gripper_mesh()
    return fixture(name).mesh

