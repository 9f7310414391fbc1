"""The simulated cell: one PyBullet world with the table, the rack, the shelf, the UR5 with its
gripper and the Kinect v2, wired to the device interfaces the application talks to.

The fixtures stand where the cell's layout says (`app.layout.CellLayout`); objects are spawned in
WORKSPACE in front of the robot; the Kinect looks at the workspace from the front. Edit
`CellConfig` (or its TOML, configs/cell.toml) to move things.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from app.layout import CellLayout, checked_vector
from app.layout import add_fixtures as add_layout_fixtures
from hardware.sim.arm import SimArm, SimArmConfig
from hardware.sim.gripper import SimGripper, SimGripperConfig
from hardware.sim.kinect import NoiseModel, SimKinect, SimKinectConfig, look_at
from hardware.sim.robot import SimRobot
from hardware.sim.world import SimWorld, SimWorldConfig

WORKSPACE = ((0.40, 0.62), (-0.12, 0.14))  # x range, y range on the table for spawned objects
CAMERA_REACH = 5.0  # m from the base: a camera farther sees nothing of the cell at the Kinect's 4.5 m range


@dataclass(frozen=True)
class CellConfig(CellLayout):
    """Where everything stands in the simulated cell: the layout, the devices' settings, the camera."""

    world: SimWorldConfig = SimWorldConfig()
    arm: SimArmConfig = SimArmConfig()
    gripper: SimGripperConfig = SimGripperConfig()
    camera_eye: tuple[float, float, float] = (1.25, 0.0, 0.55)
    camera_target: tuple[float, float, float] = (0.50, 0.0, 0.05)
    camera_seed: int = 0
    camera_noise: bool = True

    def __post_init__(self) -> None:
        super().__post_init__()
        checked_vector("camera_eye", self.camera_eye, 3, CAMERA_REACH)
        checked_vector("camera_target", self.camera_target, 3, CAMERA_REACH)
        if math.dist(self.camera_eye, self.camera_target) < 0.1:
            raise ValueError(f"camera_eye {list(self.camera_eye)} and camera_target {list(self.camera_target)} "
                             f"must be at least 0.1 m apart (the camera looks from one at the other)")


def add_fixtures(world: SimWorld, config: CellLayout) -> dict[str, int]:
    """Build the rack and the shelf in a world at their configured poses; {name: body}."""
    return add_layout_fixtures(world.require(), config, world.config.mesh_margin)


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

    def refresh(self) -> None:
        """The same cell in a fresh physics client (devices reconnected, the arm home): PyBullet never
        frees a mesh shape, even when its body is removed (1.8 MB a spawned object), only a whole
        client; a long series of jobs refreshes now and then (`app.simcell.sim_job.run_series`)."""
        self.disconnect()
        self.connect()

    def __enter__(self):
        self.connect()
        return self

    def __exit__(self, *exc) -> None:
        self.disconnect()
