"""The cell's robot in a recording: the UR5 with the gripper, logged from the URDF the simulator and
the planner use (`hardware.robot_description`), with Rerun's own URDF loader (`rerun.urdf.UrdfTree`);
its state (joints, TCP, the gripper's width and force, the force on the tool) sent as columns, one
call per entity, for any number of samples; and what is logged in the UR `base` frame."""
from __future__ import annotations

import numpy as np
import rerun as rr

from app.recording import layout as L
from hardware.se3 import ur_to_pose
from hardware.robot_description import cell_robot_urdf, write_cached

ARM_JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
              "wrist_3_joint")


def log_in_base(rec: rr.RecordingStream, path: str, archetype, static: bool = False) -> None:
    """Log at `path` in the UR base frame (the URDF's `base` link), the frame of every pose we report."""
    rec.log(path, rr.CoordinateFrame("base"), static=True)
    rec.log(path, archetype, static=static)


class RobotModel:
    """The URDF's tree: its meshes logged once, the arm's state sent as columns."""

    def __init__(self) -> None:
        self.tree = rr.urdf.UrdfTree.from_file_path(write_cached("ur5_nift_gripper", cell_robot_urdf()),
                                                    entity_path_prefix=L.ROBOT)
        self.joints = [self.tree.get_joint_by_name(name) for name in ARM_JOINTS]

    def log_model(self, rec: rr.RecordingStream) -> None:
        """The meshes and the fixed transforms (static)."""
        self.tree.log_urdf_to_recording(rec)

    def send_state(self, rec: rr.RecordingStream, times: list[rr.TimeColumn], q: np.ndarray, tcp: np.ndarray,
                   width: np.ndarray, grip: np.ndarray, tool_force: np.ndarray) -> None:
        """T samples at `times`: joints q (T, 6) as each joint's transform and as plots, the TCP (T, 6; UR
        poses), the gripper's width (T,) and force (T,), the force on the tool (T, 6) as |F|."""
        for i, joint in enumerate(self.joints):
            rec.send_columns(f"{L.ROBOT}/joints/{joint.name}", indexes=times,
                             columns=joint.compute_transform_columns(q[:, i], clamp=False))
            rec.send_columns(f"{L.JOINTS}/j{i + 1}", indexes=times, columns=rr.Scalars.columns(scalars=q[:, i]))
        for path, values in ((L.GRIPPER_WIDTH, width), (L.GRIPPER_FORCE, grip),
                             (L.TOOL_FORCE, np.linalg.norm(tool_force[:, :3], axis=1))):
            rec.send_columns(path, indexes=times, columns=rr.Scalars.columns(scalars=values))
        poses = [ur_to_pose(p) for p in tcp]
        rec.log(L.TCP, rr.CoordinateFrame("base"), static=True)
        rec.send_columns(L.TCP, indexes=times, columns=rr.Transform3D.columns(
            translation=[T[:3, 3] for T in poses], mat3x3=[T[:3, :3] for T in poses]))
