"""The cell's robot in a recording: the UR5 with the gripper, logged from the URDF the simulator and
the planner use (`hardware.robot_description`), with Rerun's own URDF loader (`rerun.urdf.UrdfTree`),
and its six joints animated from sampled joint angles as columns (one call per joint, not per sample)."""
from __future__ import annotations

import numpy as np
import rerun as rr

from app.recording.layout import ROBOT
from hardware.robot_description import cell_robot_urdf, write_cached

ARM_JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
              "wrist_3_joint")


class RobotModel:
    """The URDF's tree: its meshes logged once, its joints' transforms sent as columns."""

    def __init__(self) -> None:
        self.tree = rr.urdf.UrdfTree.from_file_path(write_cached("ur5_nift_gripper", cell_robot_urdf()),
                                                    entity_path_prefix=ROBOT)
        self.joints = [self.tree.get_joint_by_name(name) for name in ARM_JOINTS]

    def log_model(self, rec: rr.RecordingStream) -> None:
        """The meshes and the fixed transforms (static)."""
        self.tree.log_urdf_to_recording(rec)

    def send_joints(self, rec: rr.RecordingStream, times: list[rr.TimeColumn], q: np.ndarray) -> None:
        """The arm's joint angles q (T, 6) at the times given, as each joint's transform."""
        for i, joint in enumerate(self.joints):
            rec.send_columns(f"{ROBOT}/joints/{joint.name}", indexes=times,
                             columns=joint.compute_transform_columns(q[:, i], clamp=False))
