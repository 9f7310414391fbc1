"""Turn a predicted grasp so its fingers close along the surface normal of what lies between them.

Our addition (not in the paper), applied to every method alike, like `app.predict.grasp_centering`. In the
fused bench the lowest-loss NIFT rim grasps of mugs and bowls came tilted 11-28 degrees off the
rim's wall: the flat pads then touch the wall along an edge and the object slips out on the lift
(traced on 16 upright trials that failed: turned as below, 15 held; `scripts/diagnose/diagnose_grasp_slips.py`).
Antipodal grasp planners score the same thing - the closing axis against the contact normals.

With S the cloud points inside the volume the closing fingers sweep (`swept_mask`) and n_p their
unit normals (Open3D, sign-free), the wall's direction is the axis most parallel to them,

    n* = argmax_{|n| = 1}  sum_{p in S} (n . n_p)^2     (top eigenvector of sum n_p n_p^T),

and the gripper turns about its TCP by the smallest rotation taking its closing axis y onto n*
(the sign of n* nearest y). Left as it is: fewer than `min_points` points in S, or a turn over
`max_angle` (then the fingers close on something other than one wall - nothing to square up to).

It needs normals that are right: on fused clouds the teacher's own (square) bowl and mug grasps
turn by a median of 3-7 degrees (at most 18), on one Kinect view's by 2-10 (at most 89), and there
it lost more grasps than it mended (docs/additions.md, "Grasp alignment"; `scripts/diagnose/diagnose_grasp_alignment.py`)
- so callers turn it on for fused clouds only.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from app.predict.grasp_centering import MIN_POINTS, swept_mask
from hardware.gripper_geometry import GripperGeometry

NORMAL_NEIGHBOURS = 12  # points per normal estimate (Open3D's k-nearest search)
MAX_ANGLE = np.radians(45.0)  # larger turns are left undone


def surface_normals(cloud: np.ndarray, neighbours: int = NORMAL_NEIGHBOURS) -> np.ndarray:
    """Unit normals (N, 3) of a cloud (N, 3), sign arbitrary: Open3D's PCA over k nearest points."""
    import open3d as o3d

    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.asarray(cloud, float)))
    pc.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(neighbours))
    return np.asarray(pc.normals)


def wall_direction(normals: np.ndarray) -> np.ndarray:
    """n* (3,): the unit axis most parallel to the normals (K, 3) - top eigenvector of sum n n^T."""
    _, vectors = np.linalg.eigh(normals.T @ normals)  # eigenvalues ascending
    return vectors[:, -1]


def align_grasp(T_base_tcp: np.ndarray, cloud: np.ndarray, normals: np.ndarray | None = None,
                geometry: GripperGeometry = GripperGeometry(), min_points: int = MIN_POINTS,
                max_angle: float = MAX_ANGLE) -> np.ndarray:
    """T_base_tcp turned about its TCP so its closing axis (y) lies along n* of the swept points."""
    cloud = np.asarray(cloud, float).reshape(-1, 3)
    inside = swept_mask(T_base_tcp, cloud, geometry)
    if inside.sum() < min_points:
        return T_base_tcp.copy()
    n = normals[inside] if normals is not None else surface_normals(cloud)[inside]  # (K, 3)
    n = n[np.isfinite(n).all(axis=1) & (np.linalg.norm(n, axis=1) > 0.5)]  # degenerate neighbourhoods give none
    if len(n) < min_points:
        return T_base_tcp.copy()
    y = T_base_tcp[:3, 1]
    d = wall_direction(n)
    d = d if d @ y >= 0 else -d
    axis = np.cross(y, d)
    angle = float(np.arctan2(np.linalg.norm(axis), y @ d))
    if not 1e-9 <= angle <= max_angle:
        return T_base_tcp.copy()
    out = T_base_tcp.copy()
    out[:3, :3] = Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle).as_matrix() @ T_base_tcp[:3, :3]
    return out
