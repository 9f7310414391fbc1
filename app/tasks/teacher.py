"""The scripted teacher: grasp and place poses from a procedural object's known landmarks.

It stands in for the operator when recording the shipped demos, and is the benchmark's oracle.
Poses are in the object's canonical frame (scaled instance) or the fixture's frame.
"""
from __future__ import annotations

import numpy as np
import trimesh

from app.nift.raycast import cast, make_scene
from app.objects import Fixture, Semantics, semantics
from hardware.se3 import make_pose

# Tool frame at the TCP: z out of the flange (the approach direction), fingers close along y.
GRASP_DEPTH = {"mug": 0.025, "bowl": 0.012, "vase": 0.02}  # fingertips below the rim, metres
TIP_BELOW_TCP = 0.02  # fingertips are this far along the tool z past the TCP (GripperGeometry)


def outer_radii_at(mesh: trimesh.Trimesh, heights: list[float]) -> np.ndarray:
    """Outer radius of a body of revolution at each height, on its -x side (rays cast from outside)."""
    far = float(mesh.extents.max()) * 2
    rays = np.array([[-far, 0.0, z, 1.0, 0.0, 0.0] for z in heights])
    return far - cast(make_scene(mesh.vertices, mesh.faces), rays).astype(np.float64)


def grasp_pose(mesh: trimesh.Trimesh) -> np.ndarray:
    """T_obj_tcp for a (scaled) generated instance: a rim grasp from above on the side away from
    the handle (mug, bowl, vase), fingers tilted to the wall's slope; or a side grasp of the neck
    (bottle). The mesh's scale is read from its extents against the semantics."""
    sem = semantics(mesh)
    scale = float(mesh.extents[2] / sem.height)
    if sem.category == "bottle":
        # approach horizontally along +x towards the neck; fingers close along y
        R = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]).T
        return make_pose(R, [0.0, 0.0, sem.neck_height * scale])
    wall = (sem.rim_radius - (sem.rim_inner_radius or sem.rim_radius)) * scale
    top = sem.rim_height * scale
    depth = GRASP_DEPTH[sem.category] * scale
    r_top, r_low = outer_radii_at(mesh, [top - 0.002, top - depth])
    tilt = np.arctan2(r_top - r_low, depth - 0.002)  # wall leans outwards by this angle
    # tool z down along the wall (towards the axis as it descends), y across the wall, x tangential
    z_axis = np.array([np.sin(tilt), 0.0, -np.cos(tilt)])
    y_axis = np.array([np.cos(tilt), 0.0, np.sin(tilt)])
    R = np.column_stack([np.cross(y_axis, z_axis), y_axis, z_axis])
    mid = np.array([-(r_top + r_low) / 2 + wall / 2, 0.0, top - depth / 2])  # middle of the gripped wall
    tcp = mid + (depth / 2 - TIP_BELOW_TCP) * z_axis  # fingertips end `depth` below the rim
    return make_pose(R, tcp)


def hang_pose(sem: Semantics, rack: Fixture, scale: float = 1.0, along: float = 0.6) -> np.ndarray:
    """T_rack_obj: the mug's handle hole threaded on the peg, `along` of the way to the tip."""
    d = np.array(rack.landmarks["peg_direction"])
    point = np.array(rack.landmarks["peg_origin"]) + along * rack.landmarks["peg_length"] * d
    down = np.array([0.0, 0.0, -1.0])
    hang = down - (down @ d) * d
    hang /= np.linalg.norm(hang)
    R = np.column_stack([-hang, d, np.cross(-hang, d)])  # handle (+x) up the peg side, hole axis on the peg
    return make_pose(R, point - R @ (np.array(sem.handle_center) * scale))


def shelf_pose(sem: Semantics, shelf: Fixture, yaw: float = 0.0, clearance: float = 0.003) -> np.ndarray:
    """T_shelf_obj: upright in the middle of the shelf board, just above it."""
    c, s = np.cos(yaw), np.sin(yaw)
    top = np.array(shelf.landmarks["top_center"])
    return make_pose(np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]), top + [0.0, 0.0, clearance])
