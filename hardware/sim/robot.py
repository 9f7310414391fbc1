"""The simulated robot body: the installed UR5 URDF with our gripper fixed to tool0, in a SimWorld.

The arm and the gripper devices share this one multibody, as the real arm and gripper share a
flange. The URDF is assembled at run time from the example-robot-data file (package:// URIs
resolved) and the gripper fragment, and written to the cache - nothing is copied into the repo.
"""
from __future__ import annotations

import numpy as np

from hardware.bullet import joint_and_link_indices, load_cell_robot, p, pybullet_to_pose
from hardware.gripper_geometry import FINGER_JOINTS, FINGER_LINKS, GripperGeometry
from hardware.kinematics import JOINT_NAMES, UR5Kinematics
from hardware.robot_description import HOME_Q
from hardware.sim.world import SimWorld


def set_pad_friction(body: int, finger_links: list[int], geometry: GripperGeometry, client: int) -> None:
    """Give the finger links the gripper's pad friction."""
    for link in finger_links:
        p.changeDynamics(body, link, lateralFriction=geometry.pad_friction, spinningFriction=0.01,
                         frictionAnchor=1, physicsClientId=client)


class SimRobot:
    """Loads the UR5 + gripper into a world once and knows its joint and link indices."""

    def __init__(self, world: SimWorld, geometry: GripperGeometry = GripperGeometry()) -> None:
        self.world = world
        self.geometry = geometry
        self.kinematics = UR5Kinematics(tcp_offset=geometry.T_tool0_tcp)
        self.body: int | None = None
        self.arm_joints: list[int] = []
        self.finger_joints: list[int] = []
        self.finger_links: list[int] = []
        self.links: dict[str, int] = {}

    @property
    def client(self) -> int:
        return self.world.require()

    def load(self) -> int:
        """Load the body if not yet loaded; place the URDF root so that UR `base` = world."""
        if self.body is not None:
            return self.body
        self.world.connect()
        T_world_root = np.linalg.inv(self.kinematics.T_world_base)  # URDF root, seen from UR base
        self.body = load_cell_robot(self.client, self.geometry, T_world_root)
        names, self.links = joint_and_link_indices(self.body, self.client)
        self.arm_joints = [names[n] for n in JOINT_NAMES]
        self.finger_joints = [names[n] for n in FINGER_JOINTS]
        self.finger_links = [self.links[n] for n in FINGER_LINKS]
        set_pad_friction(self.body, self.finger_links, self.geometry, self.client)
        self.reset_arm(HOME_Q)
        return self.body

    def reset_arm(self, q: np.ndarray) -> None:
        """Teleport the arm joints to q at rest and hold them there."""
        for j, qi in zip(self.arm_joints, q):
            p.resetJointState(self.body, j, float(qi), 0.0, physicsClientId=self.client)
        self.command_arm(np.asarray(q, float), np.zeros(6))

    def command_arm(self, q: np.ndarray, qd: np.ndarray, kp: float = 0.4, kd: float = 1.0) -> None:
        """Position-control targets for the six arm joints (forces from the URDF efforts)."""
        forces = [150.0, 150.0, 150.0, 28.0, 28.0, 28.0]
        p.setJointMotorControlArray(self.body, self.arm_joints, p.POSITION_CONTROL, targetPositions=list(q),
                                    targetVelocities=list(qd), forces=forces, positionGains=[kp] * 6,
                                    velocityGains=[kd] * 6, physicsClientId=self.client)

    def arm_state(self) -> tuple[np.ndarray, np.ndarray]:
        """(q, qd) of the arm joints."""
        states = p.getJointStates(self.body, self.arm_joints, physicsClientId=self.client)
        return np.array([s[0] for s in states]), np.array([s[1] for s in states])

    def link_pose(self, link: str) -> np.ndarray:
        """World pose (4x4) of a link frame."""
        state = p.getLinkState(self.body, self.links[link], computeForwardKinematics=True,
                               physicsClientId=self.client)
        return pybullet_to_pose(state[4], state[5])
