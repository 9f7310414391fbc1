"""A fake UR5: ur_rtde's verbs over Pinocchio kinematics, every motion done at once - or stopped
where a test's script says (`Interruption`): by a contact, which contact detection reports (the arm
at rest, no protective stop), or by a protective stop."""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from hardware.fake.world import FakeWorld
from hardware.gripper_geometry import GripperGeometry
from hardware.interfaces import Arm, JointLimits, ProtectiveStopError, StopState
from hardware.kinematics import UR5Kinematics
from hardware.robot_description import HOME_Q
from hardware.se3 import interpolate_pose, pose_to_ur, ur_to_pose

LINE_SAMPLES = 20  # IK points along a moveL


@dataclass(frozen=True)
class Motion:
    """A motion the arm was asked for, as a script sees it."""

    index: int  # 1, 2, ... over the arm's life
    verb: str  # "moveJ", "moveL" or "executeTrajectory"
    q_start: np.ndarray  # (6,)
    q_end: np.ndarray  # (6,)
    guarded: bool  # under contact detection


@dataclass
class Interruption:
    """A scripted stop: the first motion `when` accepts stops `at` this share of its way, by a contact
    (`contact`; a guarded motion reports it and rests, an unguarded one ends in a protective stop) or
    a protective stop; used once unless `repeat`."""

    when: Callable[[Motion], bool]
    at: float = 0.5
    contact: bool = True
    repeat: bool = False


@dataclass(frozen=True)
class FakeArmConfig:
    home_q: tuple[float, ...] = tuple(HOME_Q)


class FakeArm(StopState, Arm):
    """An `Arm` whose motions arrive at once, unless interrupted; every motion is kept in `motions`."""

    def __init__(self, config: FakeArmConfig = FakeArmConfig(), world: FakeWorld | None = None) -> None:
        super().__init__(config)
        self.world = world or FakeWorld()
        self.kinematics = UR5Kinematics(tcp_offset=GripperGeometry().T_tool0_tcp)
        k = self.kinematics
        self._limits = JointLimits(k.lower.copy(), k.upper.copy(), k.velocity_limit.copy(),
                                   np.full(6, 8.0), np.full(6, 60.0))
        self.q = np.array(config.home_q, float)
        self.motions: list[Motion] = []
        self.interruptions: list[Interruption] = []
        self.after_motion: list[Callable[[Motion, bool], None]] = []  # (motion, arrived) after each one
        self.stops = 0  # stopJ calls
        self.clock = 0.0  # s: each motion advances it by its nominal duration (`getTimestamp`)
        self._stopped, self._teach, self._detecting, self._contact = False, False, False, False
        self._last_error = ""

    def _connect(self) -> None:
        self.q = np.array(self.config.home_q, float)

    def _disconnect(self) -> None:
        pass

    @property
    def joint_limits(self) -> JointLimits:
        return self._limits

    def getActualQ(self) -> np.ndarray:
        self.require_connected()
        return self.q.copy()

    def getActualQd(self) -> np.ndarray:
        return np.zeros(6)

    def getTimestamp(self) -> float:
        self.require_connected()
        return self.clock

    def getForwardKinematics(self, q: np.ndarray | None = None) -> np.ndarray:
        return pose_to_ur(self.kinematics.fk(self.getActualQ() if q is None else np.asarray(q, float)))

    def getActualTCPPose(self) -> np.ndarray:
        return self.getForwardKinematics()

    def setTcp(self, tcp_offset: np.ndarray) -> None:
        self.kinematics.set_tcp(ur_to_pose(tcp_offset))

    def getTCPOffset(self) -> np.ndarray:
        return pose_to_ur(self.kinematics.T_tool0_tcp)

    def moveJ(self, q: np.ndarray, speed: float = 1.05, acceleration: float = 1.4) -> bool:
        path = np.array([self.getActualQ(), np.asarray(q, float)])
        return self._move("moveJ", path, float(np.abs(path[1] - path[0]).max()) / speed)

    def moveL(self, pose: np.ndarray, speed: float = 0.25, acceleration: float = 1.2) -> bool:
        T0, T1 = self.kinematics.fk(self.getActualQ()), ur_to_pose(pose)
        path = [self.getActualQ()]
        for s in np.linspace(0.0, 1.0, LINE_SAMPLES)[1:]:
            q = self.kinematics.ik_nearest(interpolate_pose(T0, T1, s), path[-1])
            if q is None:
                self._last_error = f"moveL: no IK solution at {100 * s:.0f}% of the line"
                return False
            path.append(q)
        return self._move("moveL", np.array(path), float(np.linalg.norm(T1[:3, 3] - T0[:3, 3])) / speed)

    def executeTrajectory(self, times: np.ndarray, q: np.ndarray, qd: np.ndarray | None = None) -> bool:
        q = np.asarray(q, float)
        if np.abs(q[0] - self.getActualQ()).max() > 0.01:
            raise ValueError("trajectory does not start at the arm's current joint positions")
        return self._move("executeTrajectory", q, float(times[-1] - times[0]))

    def stopJ(self, deceleration: float = 2.0) -> None:
        self.require_connected()
        self.stops += 1

    def getActualTCPForce(self) -> np.ndarray:
        return np.zeros(6)

    def startContactDetection(self, force: float | None = None) -> bool:
        self._detecting, self._contact = True, False
        return True

    def readContactDetection(self) -> bool:
        return self._contact

    def stopContactDetection(self) -> bool:
        detected, self._detecting, self._contact = self._contact, False, False
        return detected

    def teachMode(self) -> bool:
        self._teach = True
        return True

    def endTeachMode(self) -> bool:
        self._teach = False
        return True

    def isTeachMode(self) -> bool:
        return self._teach

    def _move(self, verb: str, path: np.ndarray, seconds: float) -> bool:
        """Go along the joint path (K, 6) at once, or stop where the first matching interruption says; the
        clock advances by the motion's nominal `seconds` (its share of them when stopped)."""
        self.require_connected()
        if self._stopped:
            raise ProtectiveStopError("arm is in a protective stop; call unlockProtectiveStop() first")
        if not all(self._limits.contains(q) for q in path):
            raise ValueError(f"{verb} leaves the joint limits")
        self._last_error = ""
        motion = Motion(len(self.motions) + 1, verb, path[0].copy(), path[-1].copy(), self._detecting)
        self.motions.append(motion)
        stop = next((i for i in self.interruptions if i.when(motion)), None)
        self.clock += seconds * (1.0 if stop is None else stop.at)
        if stop is None:
            self.q = path[-1].copy()
        else:
            if not stop.repeat:
                self.interruptions.remove(stop)
            self.q = along(path, stop.at)
            if stop.contact and self._detecting:
                self._contact, self._last_error = True, "contact detected: scripted"
            else:
                self._stopped, self._last_error = True, "protective stop: scripted"
        self.world.follow(self.kinematics.fk(self.q))
        for listener in self.after_motion:
            listener(motion, stop is None)
        return stop is None


def along(path: np.ndarray, share: float) -> np.ndarray:
    """The joints (6,) `share` of the way along a joint path (K, 6), by joint distance."""
    lengths = np.r_[0.0, np.cumsum(np.abs(np.diff(path, axis=0)).sum(axis=1))]
    if lengths[-1] == 0.0:
        return path[-1].copy()
    s = float(np.clip(share, 0.0, 1.0)) * lengths[-1]
    i = int(np.clip(np.searchsorted(lengths, s) - 1, 0, len(path) - 2))
    w = (s - lengths[i]) / max(lengths[i + 1] - lengths[i], 1e-12)
    return (1 - w) * path[i] + w * path[i + 1]
