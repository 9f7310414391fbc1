"""The simulated cell: one PyBullet world with the table, the rack, the shelf, the UR5 with its
gripper and the Kinect v2, wired to the device interfaces the application talks to.

Layout (base frame, metres): the robot base at the origin on the table top (z = 0); objects are
spawned in WORKSPACE in front of it; the rack stands to its left with the peg pointing back at
the robot and up at 45 degrees; the shelf stands to its right; the Kinect looks at the workspace
from the front. Edit `CellConfig` (or its TOML, later) to move things.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.objects import fixture
from app.objects.collision import collision_model, visual_model
from app.se3 import make_pose, rotvec_to_matrix
from hardware.sim.arm import SimArm, SimArmConfig
from hardware.sim.gripper import SimGripper, SimGripperConfig
from hardware.sim.kinect import NoiseModel, SimKinect, SimKinectConfig, look_at
from hardware.sim.robot import SimRobot
from hardware.sim.world import SimWorld, SimWorldConfig

WORKSPACE = ((0.40, 0.62), (-0.12, 0.14))  # x range, y range on the table for spawned objects


@dataclass(frozen=True)
class CellConfig:
    """Where everything stands in the simulated cell."""

    world: SimWorldConfig = SimWorldConfig()
    arm: SimArmConfig = SimArmConfig()
    gripper: SimGripperConfig = SimGripperConfig()
    rack_xy_yaw: tuple[float, float, float] = (0.55, 0.40, np.pi)  # peg points back towards the robot
    shelf_xy_yaw: tuple[float, float, float] = (0.50, -0.45, 0.0)
    camera_eye: tuple[float, float, float] = (1.25, 0.0, 0.55)
    camera_target: tuple[float, float, float] = (0.50, 0.0, 0.05)
    camera_seed: int = 0
    camera_noise: bool = True

    def fixture_pose(self, name: str) -> np.ndarray:
        """T_base_fixture of 'rack' or 'shelf'."""
        x, y, yaw = self.rack_xy_yaw if name == "rack" else self.shelf_xy_yaw
        return make_pose(rotvec_to_matrix([0.0, 0.0, yaw]), [x, y, 0.0])


def add_fixtures(world: SimWorld, config: CellConfig) -> dict[str, int]:
    """Build the rack and the shelf in a world at their configured poses; {name: body}."""
    bodies = {}
    for name in ("rack", "shelf"):
        mesh = fixture(name).mesh
        bodies[name] = world.add_mesh(visual_model(mesh), collision_model(mesh), config.fixture_pose(name),
                                      rgba=(0.55, 0.4, 0.3, 1))
    return bodies


class SimCell:
    """Brings the whole simulated cell up and down; exposes arm, gripper and camera devices."""

    def __init__(self, config: CellConfig = CellConfig()) -> None:
        self.config = config
        self.world = SimWorld(config.world)
        self.robot = SimRobot(self.world)
        self.arm = SimArm(config.arm, self.robot)
        self.gripper = SimGripper(config.gripper, self.robot)
        cam = SimKinectConfig(T_base_cam=tuple(map(tuple, look_at(config.camera_eye, config.camera_target))),
                              noise=NoiseModel(enabled=config.camera_noise), seed=config.camera_seed)
        self.camera = SimKinect(cam, self.world)
        self.fixtures: dict[str, int] = {}

    def connect(self) -> None:
        """Start physics, build the fixtures, connect every device (idempotent)."""
        self.world.connect()
        if not self.fixtures:
            self.fixtures = add_fixtures(self.world, self.config)
        for device in (self.arm, self.gripper, self.camera):
            device.connect()

    def disconnect(self) -> None:
        """Disconnect the devices and stop physics."""
        for device in (self.camera, self.gripper, self.arm):
            device.disconnect()
        self.world.disconnect()
        self.fixtures.clear()
        self.robot.body = None

    def __enter__(self):
        self.connect()
        return self

    def __exit__(self, *exc) -> None:
        self.disconnect()
