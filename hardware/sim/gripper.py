"""Simulated parallel gripper behind the `Gripper` interface (force-limited prismatic fingers)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hardware.bullet import p
from hardware.interfaces import Gripper
from hardware.settings import check_ranges
from hardware.sim.robot import SimRobot

CLOSED_TOLERANCE = 0.002  # m: a closed gripper narrower than this holds nothing


@dataclass(frozen=True)
class SimGripperConfig:
    """Settings of the simulated gripper."""

    timeout: float = 2.0  # s allowed for an open or close
    settle_speed: float = 1e-3  # m/s: fingers slower than this have stopped
    forget_contacts: bool = True  # drop the fingers' kept contact points as they open (`_forget_finger_contacts`)

    def __post_init__(self) -> None:
        check_ranges(self, (("timeout", 0.0, 60.0, "s", False), ("settle_speed", 0.0, 1.0, "m/s", False)))


class SimGripper(Gripper):
    """The two-finger gripper on the simulated UR5 (or on a free-floating body for judges)."""

    def __init__(self, config: SimGripperConfig, robot: SimRobot) -> None:
        super().__init__(config)
        self.robot = robot
        self._detected = False

    def _connect(self) -> None:
        self.robot.load()
        self._drive(self.stroke / 2, self.max_force, self.robot.geometry.max_speed)

    def _disconnect(self) -> None:
        pass

    @property
    def stroke(self) -> float:
        return self.robot.geometry.stroke

    @property
    def max_force(self) -> float:
        return self.robot.geometry.max_force

    @property
    def width(self) -> float:
        self.require_connected()
        return float(sum(self._finger_state()[0]))

    @property
    def object_detected(self) -> bool:
        """Live, as a Robotiq's object status: closed on something and not since closed past it (a held
        object that slips out lets the fingers run on to closed)."""
        self.require_connected()
        return self._detected and self.width > CLOSED_TOLERANCE

    @property
    def force(self) -> float:
        """The fingers' motors' applied force (N), the mean of the two."""
        self.require_connected()
        states = p.getJointStates(self.robot.body, self.robot.finger_joints, physicsClientId=self.robot.client)
        return float(np.mean([abs(s[3]) for s in states]))

    def open(self, speed: float = 0.1, width: float | None = None) -> None:
        self.require_connected()
        if width is not None and not 0.0 < width <= self.stroke:
            raise ValueError(f"gripper opening must be in (0, {self.stroke}] m, got {width}")
        self._detected = False
        if self.config.forget_contacts:
            self._forget_finger_contacts()
        self._drive((self.stroke if width is None else width) / 2, self.max_force, speed)

    def close(self, force: float = 40.0, speed: float = 0.05) -> bool:
        self.require_connected()
        if not 0.0 < force <= self.max_force:
            raise ValueError(f"grip force must be in (0, {self.max_force}] N, got {force}")
        self._drive(0.0, force, speed)
        self._detected = self.width > CLOSED_TOLERANCE
        return self._detected

    def _forget_finger_contacts(self) -> None:
        """Drop the contact points Bullet keeps between the fingers and what they touch, so that the
        opening starts from contacts found afresh in the geometry.

        Bullet carries a pair's contact points from step to step (its persistent manifold) and
        refreshes their depth along the normal each was found with. A point kept with its normal
        reversed (a pad pressed into a thin rim's convex parts) holds the object to the pad: opening
        fingers dragged the oracle's bowls 2 cm along and the retreat carried them off the shelf
        (docs/journal/jobs-2026-11-to-12-05.md, "Objects dragged off the shelf on the release").
        Switching the touched pairs'
        collisions off for one step empties their manifolds; nothing is pressed that step, as the
        fingers are letting go. No contact, no step: an open gripper's opening is unchanged."""
        r = self.robot
        pairs = {(link, c[2], c[4]) for link in r.finger_links
                 for c in p.getContactPoints(bodyA=r.body, linkIndexA=link, physicsClientId=r.client) if c[2] != r.body}
        if not pairs:
            return
        for enable in (0, 1):
            for link, body, other_link in sorted(pairs):
                p.setCollisionFilterPair(r.body, body, link, other_link, enable, physicsClientId=r.client)
            if not enable:
                r.world.step()

    def _finger_state(self) -> tuple[np.ndarray, np.ndarray]:
        states = p.getJointStates(self.robot.body, self.robot.finger_joints, physicsClientId=self.robot.client)
        return np.array([s[0] for s in states]), np.array([s[1] for s in states])

    def _command(self, target: float, force: float, speed: float) -> None:
        # maxVelocity of the motor, not changeDynamics(maxJointVelocity): that one is per multibody
        # in Bullet and would slow the arm joints too.
        for j in self.robot.finger_joints:
            p.setJointMotorControl2(self.robot.body, j, p.POSITION_CONTROL, targetPosition=target, force=force,
                                    positionGain=0.05, maxVelocity=max(speed, 1e-3) / 2,
                                    physicsClientId=self.robot.client)

    def _drive(self, target: float, force: float, speed: float) -> None:
        """Move both fingers towards target until they stop (reached or blocked) or time out."""
        world = self.robot.world
        self._command(target, force, min(speed, self.robot.geometry.max_speed))
        dt = world.config.time_step
        still = 0
        for _ in range(int(self.config.timeout / dt)):
            world.step()
            qd = self._finger_state()[1]
            still = still + 1 if np.abs(qd).max() < self.config.settle_speed / 2 else 0
            if still >= 10:  # stopped: at the target, or blocked by an object
                break
