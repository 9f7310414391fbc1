"""Grasps backed off the table (our addition, for the cell; the teleported judges let fingers pass
through the table, as NDF's protocol does).

An imitated grasp low on a wall (a bowl's side 2-3 cm under its rim) leaves the open fingertips
in the table. Backed off along its approach axis z (tool frame) by s, the open gripper's lowest
corner rises by s (-z_base . a), a the approach axis in the base frame:

    s = (table_z + clearance - lowest(T)) / (-a_z),     only for a_z < -MIN_DOWN and s <= most

and the grasp closes higher on the same wall. It is kept only if the fingers still close on as
many cloud points as a grasp must (`app.predict.feasibility.grip_points`); otherwise, and for an
approach that does not point down, the grasp is left as it is.
"""
from __future__ import annotations

import numpy as np

from app.predict.feasibility import grip_points
from app.predict.grasp_centering import swept_points
from hardware.gripper_geometry import lowest_point
from hardware.se3 import make_pose

MIN_DOWN = 0.3  # the approach axis must point at least this much down (cosine)


def backed_off_table(T_base_tcp: np.ndarray, cloud: np.ndarray, table_z: float = 0.0, clearance: float = 0.008,
                     most: float = 0.03) -> np.ndarray:
    """T_base_tcp moved back along its approach axis until the open gripper is `clearance` above the
    table top at `table_z`, by at most `most` metres, when the fingers still close on the object."""
    low = lowest_point(T_base_tcp) - table_z
    down = -float(T_base_tcp[2, 2])  # how much the approach axis points down
    if low >= clearance or down < MIN_DOWN:
        return T_base_tcp
    s = (clearance - low) / down
    if s > most:
        return T_base_tcp
    moved = T_base_tcp @ make_pose(t=[0.0, 0.0, -s])
    return moved if len(swept_points(moved, cloud)) >= grip_points(cloud) else T_base_tcp
