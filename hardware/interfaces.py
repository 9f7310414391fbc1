"""Device interfaces: what a driver for the real cell must offer, and what the simulator implements.

The contract follows LeRobot's devices (a config dataclass, idempotent `connect()` /
`disconnect()`, a context manager, `DeviceNotConnectedError` when used while disconnected) and,
for the arm, ur_rtde's verbs (`moveJ`, `moveL`, `getActualQ`, `getActualTCPPose`, `stopJ`, ...).
Units are SI; Cartesian poses at this boundary are UR-style `[x, y, z, rx, ry, rz]` (rotation
vector) in the robot's base frame, which is the world frame of the whole application.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np


class DeviceNotConnectedError(RuntimeError):
    """A device was used before `connect()` or after `disconnect()`."""


class ProtectiveStopError(RuntimeError):
    """The arm is in a protective stop; motion is refused until it is unlocked."""


class DeviceConnectionLost(ConnectionError):
    """The link to a device's controller is gone (it stopped answering): nothing more can be asked of it."""


@dataclass(frozen=True)
class JointLimits:
    """Per-joint limits of an arm (radians, rad/s, rad/s^2, rad/s^3)."""

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray

    def contains(self, q: np.ndarray, tol: float = 1e-9) -> bool:
        """True when every joint of q is within [lower, upper]."""
        q = np.asarray(q)
        return bool(np.all(q >= self.lower - tol) and np.all(q <= self.upper + tol))


@dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics of a depth image (pixels)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    @property
    def matrix(self) -> np.ndarray:
        """3x3 camera matrix K."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class Frame:
    """One RGB-D capture: colour registered to depth, depth in metres (0 = invalid)."""

    color: np.ndarray  # (H, W, 3) uint8
    depth: np.ndarray  # (H, W) float32, metres along the optical axis, 0 where invalid
    intrinsics: CameraIntrinsics
    timestamp: float  # seconds (device clock)


class Device(ABC):
    """Connect / disconnect lifecycle shared by every device."""

    name: str = "device"

    def __init__(self, config: Any) -> None:
        self.config = config
        self._connected = False

    @property
    def is_connected(self) -> bool:
        """True between `connect()` and `disconnect()`."""
        return self._connected

    def connect(self) -> None:
        """Open the device; calling it again while connected does nothing."""
        if not self._connected:
            self._connect()
            self._connected = True

    def disconnect(self) -> None:
        """Release the device; calling it again while disconnected does nothing."""
        if self._connected:
            self._disconnect()
            self._connected = False

    def require_connected(self) -> None:
        """Raise DeviceNotConnectedError unless connected."""
        if not self._connected:
            raise DeviceNotConnectedError(f"{self.name} is not connected; call connect() first")

    def __enter__(self):
        self.connect()
        return self

    def __exit__(self, *exc) -> None:
        self.disconnect()

    @abstractmethod
    def _connect(self) -> None: ...

    @abstractmethod
    def _disconnect(self) -> None: ...


class Arm(Device):
    """A 6-axis arm with a UR-style controller interface."""

    name = "arm"

    @property
    @abstractmethod
    def joint_limits(self) -> JointLimits: ...

    @abstractmethod
    def getActualQ(self) -> np.ndarray:
        """Measured joint positions (6,), radians."""

    @abstractmethod
    def getActualQd(self) -> np.ndarray:
        """Measured joint velocities (6,), rad/s."""

    @abstractmethod
    def getTimestamp(self) -> float:
        """Seconds on the controller's clock (ur_rtde's `RTDEReceiveInterface.getTimestamp`)."""

    @abstractmethod
    def getActualTCPPose(self) -> np.ndarray:
        """TCP pose [x, y, z, rx, ry, rz] in the base frame, with the current TCP offset."""

    @abstractmethod
    def setTcp(self, tcp_offset: np.ndarray) -> None:
        """TCP offset [x, y, z, rx, ry, rz] from the flange (tool0)."""

    @abstractmethod
    def getTCPOffset(self) -> np.ndarray:
        """The current TCP offset [x, y, z, rx, ry, rz]."""

    @abstractmethod
    def getForwardKinematics(self, q: np.ndarray | None = None) -> np.ndarray:
        """TCP pose [x, y, z, rx, ry, rz] at joint positions q (default: the actual ones)."""

    @abstractmethod
    def moveJ(self, q: np.ndarray, speed: float = 1.05, acceleration: float = 1.4) -> bool:
        """Move to joint positions (blocking); speed in rad/s, acceleration in rad/s^2.

        Returns True on arrival; False if stopped (protective stop, stopJ)."""

    @abstractmethod
    def moveL(self, pose: np.ndarray, speed: float = 0.25, acceleration: float = 1.2) -> bool:
        """Move the TCP on a straight line to pose (blocking); m/s, m/s^2."""

    @abstractmethod
    def executeTrajectory(self, times: np.ndarray, q: np.ndarray, qd: np.ndarray | None = None) -> bool:
        """Follow a timed joint trajectory (T,), (T, 6) [, (T, 6)] starting at the current q."""

    @abstractmethod
    def stopJ(self, deceleration: float = 2.0) -> None:
        """Decelerate the joints to rest."""

    @abstractmethod
    def isProtectiveStopped(self) -> bool:
        """True while a protective stop is active."""

    @abstractmethod
    def unlockProtectiveStop(self) -> None:
        """Clear a protective stop."""

    @abstractmethod
    def getLastError(self) -> str:
        """Why the last motion did not complete ('' if it did)."""

    @abstractmethod
    def getActualTCPForce(self) -> np.ndarray:
        """External wrench on the tool [Fx, Fy, Fz, Tx, Ty, Tz] (N, N m) in the base frame, about the TCP."""

    @abstractmethod
    def startContactDetection(self, force: float | None = None) -> bool:
        """Until stopContactDetection(): a motion ends early, at rest and without a protective stop, once
        the tool meets something: the external force on it changes, from what it is now, by more than
        `force` N (None: the controller's own threshold)."""

    @abstractmethod
    def readContactDetection(self) -> bool:
        """True if a contact stopped a motion since startContactDetection()."""

    @abstractmethod
    def stopContactDetection(self) -> bool:
        """End contact detection; True if a contact was detected meanwhile."""

    @abstractmethod
    def teachMode(self) -> bool:
        """Freedrive: the joints yield to the operator's hand until endTeachMode(); motions are refused meanwhile."""

    @abstractmethod
    def endTeachMode(self) -> bool:
        """Leave freedrive: the arm holds where the operator left it and takes motions again."""

    @abstractmethod
    def isTeachMode(self) -> bool:
        """True while in freedrive."""


class StopState:
    """What an arm's controller keeps about its last stop, as ur_rtde reports it: a protective stop
    until unlocked, and the last motion's error ('' when it completed). Implementations set
    `_stopped` and `_last_error` where their motions end."""

    _stopped: bool = False
    _last_error: str = ""

    def isProtectiveStopped(self) -> bool:
        return self._stopped

    def unlockProtectiveStop(self) -> None:
        self._stopped = False

    def getLastError(self) -> str:
        return self._last_error


class Gripper(Device):
    """A parallel two-finger gripper."""

    name = "gripper"

    @property
    @abstractmethod
    def stroke(self) -> float:
        """Maximum opening between the finger pads, metres."""

    @property
    @abstractmethod
    def max_force(self) -> float:
        """Maximum grip force, newtons."""

    @abstractmethod
    def open(self, speed: float = 0.1, width: float | None = None) -> None:
        """Open fully, or to `width` metres between the pads (blocking)."""

    @abstractmethod
    def close(self, force: float = 40.0, speed: float = 0.05) -> bool:
        """Close with a force limit (blocking); True if an object stopped the fingers."""

    @property
    @abstractmethod
    def width(self) -> float:
        """Current opening between the finger pads, metres."""

    @property
    @abstractmethod
    def object_detected(self) -> bool:
        """True when the fingers stopped on something before closing fully."""

    @property
    @abstractmethod
    def force(self) -> float:
        """The force the fingers press with now, newtons (a Robotiq's motor current, as a force): up to
        the closing force on a held object, about 0 when open or closed on nothing."""


class DepthCamera(Device):
    """An RGB-D camera delivering depth registered colour."""

    name = "camera"

    @property
    @abstractmethod
    def intrinsics(self) -> CameraIntrinsics: ...

    @abstractmethod
    def capture(self) -> Frame:
        """One frame: colour, depth in metres (0 = invalid), timestamp."""
