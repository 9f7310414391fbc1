"""Grasps backed off the object under the palm (our addition, for the cell).

An imitated grasp deep on a wall (a rim grasp 5 cm down a mug's side) puts the palm, 4 cm behind
the TCP, into the rim. The guarded approach stops on such a contact only once the force has lasted
`contact_detection_time`, and a stiff palm-on-rim contact passes the protective limit first. So the
grasp is moved back along its approach axis z (tool frame) by

    s = max_i (z_front + clearance - z_i),    over the seen points i inside the palm's box,

z_front the palm's front face (TCP frame), when s <= `most`, the palm's box is then clear and the
fingers still close on as many cloud points as a grasp must (`app.predict.feasibility.grip_points`);
otherwise the grasp is left as it is (the job's approach test, `app.jobs.clearance`, judges it).
"""
from __future__ import annotations

import numpy as np

from app.predict.feasibility import grip_points
from app.predict.grasp_centering import swept_points
from app.predict.table_clearance import backed_off_table
from hardware.gripper_geometry import GripperGeometry
from hardware.se3 import make_pose


def palm_overlap(T_base_tcp: np.ndarray, cloud: np.ndarray, clearance: float,
                 geometry: GripperGeometry = GripperGeometry()) -> float:
    """How far (m) the palm's box reaches past the cloud's (N, 3) points inside it, grown by `clearance`
    on its front face: 0 when none lies there."""
    (px, py, pz), front = geometry.palm, geometry.palm[2] - geometry.tcp_z  # front face, TCP frame
    p = (np.asarray(cloud, float) - T_base_tcp[:3, 3]) @ T_base_tcp[:3, :3]  # (N, 3) TCP frame
    inside = (np.abs(p[:, 0]) <= px / 2) & (np.abs(p[:, 1]) <= py / 2) & (p[:, 2] >= front - pz) & (
        p[:, 2] < front + clearance)
    return float((front + clearance - p[inside, 2]).max()) if inside.any() else 0.0


def backed_off_palm(T_base_tcp: np.ndarray, cloud: np.ndarray, clearance: float = 0.003,
                    most: float = 0.02) -> np.ndarray:
    """T_base_tcp moved back along its approach axis until no seen point lies within `clearance` of the
    palm's front face, by at most `most` metres, when the fingers still close on the object."""
    s = palm_overlap(T_base_tcp, cloud, clearance)
    if s == 0.0 or s > most:
        return T_base_tcp
    moved = T_base_tcp @ make_pose(t=[0.0, 0.0, -s])
    if palm_overlap(moved, cloud, 0.0) > 0.0 or len(swept_points(moved, cloud)) < grip_points(cloud):
        return T_base_tcp
    return moved


def seated(T_base_tcp: np.ndarray, cloud: np.ndarray, table_z: float = 0.0) -> np.ndarray:
    """A grasp as the cell makes it: backed off the table (`backed_off_table`), then off what lies under
    the palm (`backed_off_palm`)."""
    return backed_off_palm(backed_off_table(T_base_tcp, cloud, table_z), cloud)
