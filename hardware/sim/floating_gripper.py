"""A free-floating copy of the gripper, moved by a constraint: what the grasp judge closes on an
object without involving the arm (NDF's teleported evaluation)."""
from __future__ import annotations

import numpy as np

from hardware.bullet import joint_and_link_indices, p, pose_to_pybullet
from hardware.gripper_geometry import FINGER_JOINTS, FINGER_LINKS, GripperGeometry, standalone_gripper_urdf
from hardware.robot_description import write_cached
from hardware.sim.robot import set_pad_friction
from hardware.sim.world import SimWorld


class FloatingGripper:
    """Same attributes as SimRobot that SimGripper uses (body, finger joints, world, geometry)."""

    def __init__(self, world: SimWorld, T_world_tool0: np.ndarray, geometry: GripperGeometry = GripperGeometry()):
        self.world = world
        self.geometry = geometry
        self.T = np.asarray(T_world_tool0, float)
        self.body: int | None = None
        self.constraint: int | None = None
        self.finger_joints: list[int] = []
        self.finger_links: list[int] = []

    @property
    def client(self) -> int:
        return self.world.require()

    def load(self) -> int:
        """Create the body at its pose, held by a fixed constraint."""
        if self.body is not None:
            return self.body
        path = write_cached("nift_gripper", standalone_gripper_urdf(self.geometry))
        pos, quat = pose_to_pybullet(self.T)
        self.body = p.loadURDF(str(path), pos, quat, physicsClientId=self.client)
        joints, links = joint_and_link_indices(self.body, self.client)
        self.finger_joints = [joints[n] for n in FINGER_JOINTS]
        self.finger_links = [links[n] for n in FINGER_LINKS]
        for j in self.finger_joints:
            p.resetJointState(self.body, j, self.geometry.stroke / 2, physicsClientId=self.client)
        set_pad_friction(self.body, self.finger_links, self.geometry, self.client)
        self.constraint = p.createConstraint(self.body, -1, -1, -1, p.JOINT_FIXED, [0, 0, 0], [0, 0, 0], pos, [0, 0, 0, 1],
                                             quat, physicsClientId=self.client)
        p.changeConstraint(self.constraint, pos, quat, maxForce=2000, physicsClientId=self.client)
        return self.body

    def move_to(self, T_world_tool0: np.ndarray) -> None:
        """Set the constraint's target pose (the body follows over the next steps)."""
        self.T = np.asarray(T_world_tool0, float)
        pos, quat = pose_to_pybullet(self.T)
        p.changeConstraint(self.constraint, pos, quat, maxForce=2000, physicsClientId=self.client)

    def remove(self) -> None:
        """Take the gripper out of the world."""
        if self.body is not None:
            p.removeConstraint(self.constraint, physicsClientId=self.client)
            p.removeBody(self.body, physicsClientId=self.client)
            self.body = None
