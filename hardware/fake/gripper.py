"""A fake two-finger gripper: it closes on the world's object between its fingers (as wide as the
object is across them) or on nothing, and lets go when it opens - unless a test's script jams it
(`jams`) or makes the object slip out (`drop`)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hardware.fake.arm import FakeArm
from hardware.fake.world import NoLink
from hardware.gripper_geometry import GripperGeometry
from hardware.interfaces import Gripper


@dataclass(frozen=True)
class FakeGripperConfig:
    stroke: float = GripperGeometry().stroke
    max_force: float = GripperGeometry().max_force


class FakeGripper(NoLink, Gripper):
    """A `Gripper` on a `FakeArm`: what it holds follows the arm's TCP in the arm's world."""

    def __init__(self, arm: FakeArm, config: FakeGripperConfig = FakeGripperConfig()) -> None:
        super().__init__(config)
        self.arm = arm
        self._width, self._detected, self._force = config.stroke, False, 0.0
        self.jams: list[float] = []  # scripted: each opening while holding stops at the next of these widths (m)
        self.fallen: np.ndarray | None = None  # where a dropped object comes to rest (T_base_obj); None: below the TCP

    @property
    def stroke(self) -> float:
        return self.config.stroke

    @property
    def max_force(self) -> float:
        return self.config.max_force

    @property
    def width(self) -> float:
        return self._width

    @property
    def object_detected(self) -> bool:
        return self._detected

    @property
    def force(self) -> float:
        """The closing force while it holds something, else 0 (no motor to read)."""
        return self._force if self._detected else 0.0

    def close(self, force: float = 40.0, speed: float = 0.05) -> bool:
        self.require_connected()
        T_tcp = self.arm.kinematics.fk(self.arm.getActualQ())
        held = self.arm.world.between_fingers(T_tcp)
        self._force = float(force)
        if held is None:
            self._width, self._detected = 0.0, False
            return False
        across = held.in_base().vertices @ T_tcp[:3, 1]  # the fingers close along the tool's y
        self._width = float(min(self.stroke, np.ptp(across)))
        self._detected = True
        self.arm.world.grip(held, T_tcp)
        return True

    def open(self, speed: float = 0.1, width: float | None = None) -> None:
        self.require_connected()
        asked = self.stroke if width is None else float(np.clip(width, 0.0, self.stroke))
        if self._detected and self.jams:
            self._width = max(self._width, self.jams.pop(0))  # stuck on the object: it is still held
            return
        self._width, self._detected = asked, False
        self.arm.world.let_go()

    def drop(self) -> None:
        """The held object slips out: the fingers close on nothing, and it lands at `fallen`."""
        for o in self.arm.world.objects:
            if o.T_tcp_obj is not None:
                o.T_tcp_obj = None
                if self.fallen is not None:
                    o.T_base_obj = self.fallen
        self._width, self._detected = 0.0, False
