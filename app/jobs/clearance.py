"""The cell's clearance rules for grasps (our addition): the imitation's pruning keeps grasps the
cell can make before others - the open gripper, refined and backed off the table as the job will do
it, hits nothing of the cell, and on its way in along the approach line passes none of the object's
seen points (the planning scene lets the approach pass the object's hull: it must, to close on it).
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from app.motion.ik import Blocked
from app.motion.planner import OBJECT
from app.motion.scene import PlanningScene
from app.predict.predict import refine_grasp
from app.predict.palm_clearance import seated
from hardware.gripper_geometry import GripperGeometry
from hardware.se3 import make_pose


def gripper_clear(scene: PlanningScene, cloud: np.ndarray, table_z: float = 0.0, approach: float = 0.10,
                  center: bool = True, align: bool = False) -> Callable[[np.ndarray], bool]:
    """Grasp pose (4, 4) -> whether the open gripper there, refined (`center`, `align`) and seated
    (`app.predict.palm_clearance.seated`, the table top at `table_z`) as the job will do it, hits nothing
    of the cell (table, fixtures): the imitation's pruning keeps such grasps before others (a grasp from under the table or through it is
    no grasp for a cell); nor may the open gripper pass through the object's seen points on its way
    in along the last `approach` metres (`approach_clear`)."""
    def clear(T_base_tcp: np.ndarray) -> bool:
        T = seated(refine_grasp(T_base_tcp, cloud, center=center, align=align), cloud, table_z)
        return (not scene.gripper_collisions(T, ignore=(OBJECT,))
                and approach_clear(T, cloud, approach, scene.geometry))

    return clear


def approach_clear(T_base_tcp: np.ndarray, cloud: np.ndarray, distance: float, geometry: GripperGeometry,
                   margin: float = 0.002) -> bool:
    """Whether no cloud point (N, 3) lies in the volume the open gripper's palm and fingers (grown by
    `margin`) sweep along the approach line, from `distance` back along the tool axis to T_base_tcp:
    the planning scene lets the approach pass the object's hull (it must, to close on it), so a finger
    coming down on the rim instead of beside it is caught here (it stopped the arm on the line)."""
    return not approach_hits(T_base_tcp, cloud, distance, geometry, margin=margin)


def approach_hits(T_base_tcp: np.ndarray, cloud: np.ndarray, distance: float, geometry: GripperGeometry,
                  width: float | None = None, margin: float = 0.0) -> int:
    """How many cloud points (N, 3) lie in the volume the gripper, its fingers `width` apart (None: fully
    open) and its boxes grown by `margin`, sweeps along the last `distance` metres of its way in to T_base_tcp."""
    local = (np.asarray(cloud, float) - T_base_tcp[:3, 3]) @ T_base_tcp[:3, :3]  # (N, 3) TCP frame
    return int(geometry.contains(local, width, margin, sweep=distance).sum())


def approach_blocked(failure: Callable[[np.ndarray, str], Blocked | None], points: np.ndarray, distance: float,
                     width: Callable[[np.ndarray], float], geometry: GripperGeometry,
                     arrived: float) -> Callable[[np.ndarray, str], Blocked | None]:
    """The quick test `failure(T, what)` and then, at a grasp, the way in checked against the seen points
    (N, 3): the gripper, its fingers `width(T)` apart, may meet none of them along the last `distance`
    metres of the approach until `arrived` metres before the grasp (a contact that close is the grasp,
    as the guarded approach takes it); else it would stop on the line, or press on into a stop."""
    def blocked(T_base_tcp: np.ndarray, what: str = "pose") -> Blocked | None:
        if (why := failure(T_base_tcp, what)) or what != "grasp":
            return why
        short = T_base_tcp @ make_pose(t=[0.0, 0.0, -arrived])  # where the way in may first meet the object
        if n := approach_hits(short, points, distance, geometry, width(T_base_tcp)):
            return Blocked(f"the gripper's way in to the grasp passes through {n} seen points of the object")
        return None

    return blocked
