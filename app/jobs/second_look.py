"""The second look at the held object (our addition, as a person at the cell would do it): after the
lift the cell shows what it holds to the Kinect from the side the first view missed - a mug's far
side, where its handle may be - and imitates the place again from both views.

The views: the wrist's last joint turns the held object by each of `turns` about the tool axis (0:
as the lift left it, which shows the first view's side of the object as it now sits in the hand);
the TCP stays where the lift left it, over the table and in the camera's view. Perception keeps the points near
where the object now is, less the gripper's own (its boxes at the forward-kinematics pose,
`app.perception.held_object_cloud`). The object is rigid in the grasp, so a point x seen with the
TCP at T_view stood at

    x_0 = T_grasp @ inv(T_view) @ x                  (exact up to slip)

when the object was first seen: both views are fused in that frame; the job resamples them to the
first cloud's size for `app.predict.predict.predict_place` to imitate the place on, and looks for the
handle hole in all of them (`app.predict.hole_places`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.failures import OutOfJointLimits
from app.motion.executor import execute
from app.motion.planner import OBJECT, Planner
from app.perception import PerceptionConfig, held_object_cloud
from hardware.interfaces import Arm, DepthCamera, JointLimits
from hardware.se3 import invert, transform_points
from hardware.settings import check_ranges


@dataclass(frozen=True)
class SecondLookConfig:
    """Where the held object is shown from, and how its points are told from the gripper's."""

    turns: tuple[float, ...] = (0.0, np.pi)  # rad on the wrist's last joint from the lift's end, one view each
    reach: float = 0.08  # m the crop reaches beyond the first cloud's extent: a handle hidden in the first view lies up to ~7 cm past it
    gripper_margin: float = 0.01  # m: points this close to the gripper's boxes are the gripper's
    turn_speed: float = 3.0  # rad/s of the wrist's turn: within its 3.2; the fingers' axis stays put, so the held
    # object barely swings (docs/decisions.md, "The second look's turn")
    turn_acceleration: float = 8.0  # rad/s^2, within the wrist's 12

    def __post_init__(self) -> None:
        check_ranges(self, (("turn_speed", 0.0, 3.2, "rad/s", False), ("turn_acceleration", 0.0, 12.0, "rad/s^2", False)))


def view_q(q: np.ndarray, turn: float, limits: JointLimits) -> np.ndarray:
    """q with the last joint turned by `turn`, or by -turn when that one leaves the joint's limits."""
    for signed in (turn, -turn):
        out = np.array(q, float)
        out[5] += signed
        if limits.contains(out):
            return out
    raise OutOfJointLimits(f"the wrist cannot turn by {turn:.2f} rad either way from {q[5]:.2f} rad")


def to_grasp_frame(points: np.ndarray, T_base_grasp: np.ndarray, T_base_view: np.ndarray) -> np.ndarray:
    """(M, 3) points seen with the TCP at T_base_view, where they stood with the TCP at the grasp."""
    return transform_points(T_base_grasp @ invert(T_base_view), points)


def second_look(arm: Arm, camera: DepthCamera, planner: Planner, T_base_cam: np.ndarray, first: np.ndarray,
                T_base_grasp: np.ndarray, width: float, tolerance: float,
                config: SecondLookConfig = SecondLookConfig(),
                perception: PerceptionConfig = PerceptionConfig()) -> list[np.ndarray]:
    """Show the held object, first seen as the points `first` (M, 3), from each view; return each
    view's points (M_i, 3) in the grasp-time frame; the arm is left at the last view. ObjectNotSeen when
    a view shows nothing, OutOfJointLimits when the wrist cannot turn, a PlanningFailure when it cannot get there."""
    start_q = arm.getActualQ()
    radius = float(np.linalg.norm(first - first.mean(axis=0), axis=1).max()) + config.reach
    views = []
    for turn in config.turns:
        q = view_q(start_q, turn, arm.joint_limits)
        if np.abs(q - arm.getActualQ()).max() > tolerance:
            with planner.scene.holding(OBJECT, T_base_grasp), planner.scene.fingers(width):
                turn = planner.transit(arm.getActualQ(), q, "second look", ignore=(OBJECT,),
                                       profile=(config.turn_speed, config.turn_acceleration))
                execute(arm, turn, tolerance)
        T_view = planner.kin.fk(arm.getActualQ())
        near = transform_points(T_view @ invert(T_base_grasp), first.mean(axis=0, keepdims=True))[0]
        seen = held_object_cloud(camera.capture(), T_base_cam, T_view, width, near, radius, perception,
                                 planner.scene.geometry, config.gripper_margin)
        views.append(to_grasp_frame(seen, T_base_grasp, T_view))
    return views
