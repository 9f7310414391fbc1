"""One PyBullet world per cell: the client, deterministic stepping, the table and the floor.

The world frame is the robot's base frame (UR `base`): x towards the workspace, z up; the table
top is the plane z = 0, the floor is TABLE_HEIGHT below it.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hardware import bullet
from hardware.bullet import TABLE_HEIGHT, p, pybullet_to_pose
from hardware.interfaces import DeviceNotConnectedError
from hardware.settings import check_ranges


MESH_MARGIN = 0.0002  # m


@dataclass(frozen=True)
class SimWorldConfig:
    """Physics settings of the simulated cell."""

    gui: bool = False
    time_step: float = 1.0 / 240.0
    solver_iterations: int = 80
    gravity: float = -9.81
    realtime: bool = False  # pace the physics to the wall clock (a served cell, where motions take their real time)
    # m Bullet grows every convex hull of a mesh body by (objects, fixtures). Its default, 1 mm on each
    # side of a contact, closed a mug's handle hole around the rack's peg to 0-0.6 mm (docs/cell.md)
    mesh_margin: float = MESH_MARGIN

    def __post_init__(self) -> None:
        check_ranges(self, (("time_step", 0.0, 0.05, "s", False), ("solver_iterations", 1, 10_000, "iterations", True),
                            ("gravity", -50.0, 0.0, "m/s^2", True), ("mesh_margin", 0.0, 0.01, "m", True)))


class SimWorld:
    """A PyBullet physics client with the cell's static surroundings."""

    def __init__(self, config: SimWorldConfig = SimWorldConfig()) -> None:
        self.config = config
        self.client: int | None = None
        self.table: int | None = None
        self.floor: int | None = None
        self.steps = 0
        self._clock: tuple[float, int] | None = None  # (wall time, steps) when realtime pacing began
        self.on_step: list = []  # callables run after every physics step (flange accessories)

    @property
    def is_connected(self) -> bool:
        return self.client is not None

    @property
    def time(self) -> float:
        """Simulated seconds since connect."""
        return self.steps * self.config.time_step

    def connect(self) -> None:
        """Start the physics server (DIRECT, or GUI with config.gui) and build table and floor."""
        if self.client is not None:
            return
        self.client = bullet.connect(self.config.gui)
        p.setGravity(0, 0, self.config.gravity, physicsClientId=self.client)
        p.setPhysicsEngineParameter(fixedTimeStep=self.config.time_step,
                                    numSolverIterations=self.config.solver_iterations, physicsClientId=self.client)
        self.table = bullet.add_table(self.client)
        self.floor = self.add_box((6.0, 6.0, 0.1), (0.0, 0.0, -TABLE_HEIGHT - 0.05), rgba=(0.5, 0.5, 0.5, 1))
        self.steps = 0

    def disconnect(self) -> None:
        """Stop the physics server."""
        if self.client is not None:
            p.disconnect(self.client)
            self.client = None

    def require(self) -> int:
        """The client id, or DeviceNotConnectedError."""
        if self.client is None:
            raise DeviceNotConnectedError("the simulated world is not connected; call connect() first")
        return self.client

    def __enter__(self):
        self.connect()
        return self

    def __exit__(self, *exc) -> None:
        self.disconnect()

    def step(self, n: int = 1) -> None:
        """Advance the physics by n fixed steps."""
        cid = self.require()
        for _ in range(n):
            p.stepSimulation(physicsClientId=cid)
            for callback in self.on_step:
                callback()
        self.steps += n
        if self.config.realtime:
            self._pace()

    def _pace(self) -> None:
        """Sleep until the wall clock has caught up with the simulated time (restarting after a pause)."""
        now = time.monotonic()
        if self._clock is None or (self.steps - self._clock[1]) * self.config.time_step < now - self._clock[0] - 0.5:
            self._clock = (now, self.steps)
        ahead = self._clock[0] + (self.steps - self._clock[1]) * self.config.time_step - now
        if ahead > 0:
            time.sleep(ahead)

    def add_box(self, size, center, mass: float = 0.0, rgba=(0.6, 0.6, 0.6, 1), friction: float = 0.8) -> int:
        """A box body (static when mass = 0)."""
        return bullet.add_box(self.require(), size, center, mass, rgba, friction)

    def add_mesh(self, visual_obj: Path, collision_obj: Path, T_world_body: np.ndarray, mass: float = 0.0,
                 scale: float = 1.0, rgba=(0.6, 0.7, 0.9, 1), friction: float = 0.8) -> int:
        """A body from a visual OBJ and a collision OBJ (one convex hull per `o` block, grown by the
        configured `mesh_margin`)."""
        return bullet.add_mesh(self.require(), visual_obj, collision_obj, T_world_body, mass, scale, rgba, friction,
                               self.config.mesh_margin)

    def remove(self, body: int) -> None:
        """Remove a body."""
        p.removeBody(body, physicsClientId=self.require())

    def pose(self, body: int) -> np.ndarray:
        """World pose of a body's base (4x4)."""
        return pybullet_to_pose(*p.getBasePositionAndOrientation(body, physicsClientId=self.require()))

    def set_pose(self, body: int, T: np.ndarray) -> None:
        """Teleport a body (velocity zeroed)."""
        bullet.set_pose(self.require(), body, T)

    def in_contact(self, a: int, b: int) -> bool:
        """True if bodies a and b touch after the last step."""
        return len(p.getContactPoints(a, b, physicsClientId=self.require())) > 0
