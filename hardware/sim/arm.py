"""Simulated UR5 behind the `Arm` interface: a controller that plans and tracks like a real one.

moveJ: a Ruckig time-optimal, jerk-limited joint motion (state to state - the free Ruckig, never
its cloud waypoint service), tracked by PyBullet position control at the physics rate.
moveL: a straight TCP line with a jerk-limited path profile; Pinocchio IK at every control step.
A protective stop triggers on a tracking error above `tracking_error_limit` or a contact force on
an arm link above `contact_force_limit`; the arm then holds still until unlocked. With contact
detection on (ur_rtde's startContactDetection), a motion instead ends at rest, unlocked, once the
external force on the tool passes `contact_detection_force`.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from hardware.bullet import p
from hardware.interfaces import Arm, JointLimits, ProtectiveStopError, StopState
from hardware.motion_profile import ruckig_profile
from hardware.gripper_geometry import PALM_LINK
from hardware.robot_description import HOME_Q
from hardware.se3 import interpolate_pose, line_length, pose_to_ur, ur_to_pose
from hardware.settings import check_ranges
from hardware.sim.robot import SimRobot

# Documented limits beyond the URDF (which gives position and velocity only).
JOINT_ACCELERATION_LIMIT = np.array([8.0, 8.0, 8.0, 12.0, 12.0, 12.0])  # rad/s^2
JOINT_JERK_LIMIT = np.array([60.0, 60.0, 60.0, 90.0, 90.0, 90.0])  # rad/s^3
CARTESIAN_JERK = 5.0  # m/s^3 for moveL's path profile


@dataclass(frozen=True)
class SimArmConfig:
    """Settings of the simulated controller."""

    home_q: tuple[float, ...] = tuple(HOME_Q)
    tracking_error_limit: float = 0.05  # rad, any joint
    contact_force_limit: float = 150.0  # N on any arm link (not the fingers)
    settle_time: float = 0.15  # s of holding the final target after a motion
    contact_detection_force: float = 30.0  # N: by default, a change of the tool's external force this large, from
    # when contact detection started (the sensor zeroed there, as zeroFtSensor does), ends a motion under contact detection
    contact_detection_time: float = 0.02  # s the change must last (a filtered sensor: Bullet's grip contacts flicker)

    def __post_init__(self) -> None:
        check_ranges(self, (("tracking_error_limit", 0.0, 1.0, "rad", False),
                            ("contact_force_limit", 0.0, 10_000.0, "N", False), ("settle_time", 0.0, 10.0, "s", True),
                            ("contact_detection_force", 0.0, 10_000.0, "N", False),
                            ("contact_detection_time", 0.0, 1.0, "s", True)))


class SimArm(StopState, Arm):
    """The UR5 in PyBullet, driven through ur_rtde-style verbs."""

    def __init__(self, config: SimArmConfig, robot: SimRobot) -> None:
        super().__init__(config)
        self.robot = robot
        self._stopped = False
        self._last_error = ""
        self._moving = False  # a motion's control loop is running (stopJ from another thread then asks it to stop)
        self._stop_request: float | None = None  # the deceleration stopJ asked for, until the loop has stopped
        self._detecting = False  # startContactDetection() until stopContactDetection()
        self._contact_detected = False
        self._force_zero = np.zeros(3)  # N: the tool's external force when contact detection started
        self._detection_force = self.config.contact_detection_force  # N of change that counts as a contact
        self._teach = False  # freedrive (teachMode): the simulated operator's hand moves the arm (`guide`)
        self.max_tracking_error = 0.0  # rad, largest joint error during the last motion
        self.max_force_change = 0.0  # N, largest change of the tool's force since contact detection started,
        # held for `contact_detection_time` (what a threshold that large would have stopped on)
        self._recent_changes: list[float] = []
        self.on_stop: list[Callable[[str], None]] = []  # called with the reason whenever a motion halts (diagnostics)
        k = robot.kinematics
        self._limits = JointLimits(k.lower.copy(), k.upper.copy(), k.velocity_limit.copy(),
                                   JOINT_ACCELERATION_LIMIT.copy(), JOINT_JERK_LIMIT.copy())

    # lifecycle -------------------------------------------------------------------------------
    def _connect(self) -> None:
        self.robot.load()
        self.robot.reset_arm(np.array(self.config.home_q))

    def _disconnect(self) -> None:
        pass  # the body stays in the world; the world owns it

    # state -----------------------------------------------------------------------------------
    @property
    def joint_limits(self) -> JointLimits:
        return self._limits

    def getActualQ(self) -> np.ndarray:
        self.require_connected()
        return self.robot.arm_state()[0]

    def getActualQd(self) -> np.ndarray:
        self.require_connected()
        return self.robot.arm_state()[1]

    def getTimestamp(self) -> float:
        self.require_connected()
        return self.robot.world.time

    def getForwardKinematics(self, q: np.ndarray | None = None) -> np.ndarray:
        q = self.getActualQ() if q is None else np.asarray(q, dtype=np.float64)
        return pose_to_ur(self.robot.kinematics.fk(q))

    def getActualTCPPose(self) -> np.ndarray:
        return self.getForwardKinematics()

    def setTcp(self, tcp_offset: np.ndarray) -> None:
        self.robot.kinematics.set_tcp(ur_to_pose(tcp_offset))

    def getTCPOffset(self) -> np.ndarray:
        return pose_to_ur(self.robot.kinematics.T_tool0_tcp)

    # freedrive -------------------------------------------------------------------------------
    def teachMode(self) -> bool:
        self.require_connected()
        if self._stopped:
            raise ProtectiveStopError("arm is in a protective stop; call unlockProtectiveStop() first")
        self._teach = True
        return True

    def endTeachMode(self) -> bool:
        self.require_connected()
        if self._teach:
            self._teach = False
            q = self.robot.arm_state()[0]
            self.robot.command_arm(q, np.zeros(6))  # hold where the hand left it
        return True

    def isTeachMode(self) -> bool:
        return self._teach

    def guide(self, q: np.ndarray) -> None:
        """The simulated operator's hand puts the arm at q (freedrive only; a real arm is pushed, not called)."""
        self.require_connected()
        if not self._teach:
            raise RuntimeError("the arm can be guided by hand only in teach mode; call teachMode() first")
        q = np.asarray(q, dtype=np.float64)
        if q.shape != (6,) or not np.isfinite(q).all() or not self._limits.contains(q):
            raise ValueError(f"guide needs 6 finite joint positions within the limits, got {q}")
        self.robot.reset_arm(q)

    def getActualTCPForce(self) -> np.ndarray:
        """The wrench on the tool (palm and fingers) from its contacts with other bodies (normal and
        friction forces), about the TCP, in the base frame: what a wrist force-torque sensor reads with
        the tool's own weight zeroed (a held object's squeeze cancels between the fingers, its weight does not)."""
        self.require_connected()
        robot = self.robot
        tool = {robot.links[PALM_LINK], *robot.finger_links}
        p_tcp = robot.kinematics.fk(self.getActualQ())[:3, 3]  # the world is the UR base frame (SimRobot.load)
        wrench = np.zeros(6)
        for c in p.getContactPoints(bodyA=robot.body, physicsClientId=robot.client):
            if c[2] != robot.body and c[3] in tool:
                # on the tool: the normal on B points from B towards A; the friction directions are A's
                f = c[9] * np.asarray(c[7]) + c[10] * np.asarray(c[11]) + c[12] * np.asarray(c[13])
                wrench[:3] += f
                wrench[3:] += np.cross(np.asarray(c[5]) - p_tcp, f)
        return wrench

    def startContactDetection(self, force: float | None = None) -> bool:
        self.require_connected()
        if force is not None and not (np.isfinite(force) and force > 0):
            raise ValueError(f"contact detection force must be a positive number of N, got {force!r}")
        self._detection_force = self.config.contact_detection_force if force is None else float(force)
        self._detecting, self._contact_detected = True, False
        self._force_zero = self.getActualTCPForce()[:3]
        self.max_force_change, self._recent_changes = 0.0, []
        return True

    def readContactDetection(self) -> bool:
        return self._contact_detected

    def stopContactDetection(self) -> bool:
        detected = self._contact_detected
        self._detecting, self._contact_detected = False, False
        return detected

    # motion ----------------------------------------------------------------------------------
    def moveJ(self, q: np.ndarray, speed: float = 1.05, acceleration: float = 1.4) -> bool:
        self._before_motion()
        q = np.asarray(q, dtype=np.float64)
        if q.shape != (6,) or not np.isfinite(q).all():
            raise ValueError(f"moveJ needs 6 finite joint positions, got {q}")
        if not self._limits.contains(q):
            raise ValueError(f"moveJ target {np.round(q, 3).tolist()} is outside the joint limits")
        v = np.minimum(speed, self._limits.velocity)
        a = np.minimum(acceleration, self._limits.acceleration)
        traj = ruckig_profile(self.getActualQ(), q, v, a, self._limits.jerk)
        return self._track(lambda t: traj.at_time(t)[:2], traj.duration)

    def moveL(self, pose: np.ndarray, speed: float = 0.25, acceleration: float = 1.2) -> bool:
        self._before_motion()
        k = self.robot.kinematics
        T0, T1 = k.fk(self.getActualQ()), ur_to_pose(pose)
        s_len = line_length(T0, T1)  # path parameter covers rotation-only moves too
        profile = ruckig_profile(np.zeros(1), np.array([s_len]), np.array([speed]), np.array([acceleration]),
                                 np.array([CARTESIAN_JERK]))
        q_prev = [self.getActualQ()]
        dt = self.robot.world.config.time_step

        def target(t: float):
            s = float(np.clip(profile.at_time(t)[0][0] / s_len, 0.0, 1.0))  # Ruckig may overshoot by ~1e-12
            q = k.ik(interpolate_pose(T0, T1, s), q_prev[0])
            if q is None or np.abs(q - q_prev[0]).max() > 4 * self._limits.velocity.max() * dt + 1e-3:
                raise _NoIK(f"moveL: no continuous IK solution at {100 * s:.0f}% of the line")
            qd = (q - q_prev[0]) / dt
            q_prev[0] = q
            return q, qd

        return self._track(target, profile.duration)

    def executeTrajectory(self, times: np.ndarray, q: np.ndarray, qd: np.ndarray | None = None) -> bool:
        self._before_motion()
        times, q = np.asarray(times, float), np.asarray(q, float)
        if q.ndim != 2 or q.shape[1] != 6 or len(times) != len(q) or np.any(np.diff(times) <= 0):
            raise ValueError("a trajectory needs increasing times (T,) and joint positions (T, 6)")
        if np.abs(q[0] - self.getActualQ()).max() > 0.01:
            raise ValueError("trajectory does not start at the arm's current joint positions")
        if not all(self._limits.contains(qi) for qi in q):
            raise ValueError("trajectory leaves the joint limits")
        qd = np.gradient(q, times, axis=0) if qd is None else np.asarray(qd, float)

        def target(t: float):
            i = int(np.clip(np.searchsorted(times, t + times[0]) - 1, 0, len(times) - 2))
            w = np.clip((t + times[0] - times[i]) / (times[i + 1] - times[i]), 0.0, 1.0)
            return (1 - w) * q[i] + w * q[i + 1], (1 - w) * qd[i] + w * qd[i + 1]

        return self._track(target, times[-1] - times[0])

    def stopJ(self, deceleration: float = 2.0) -> None:
        """Decelerate to rest; during a motion (called from another thread, as a device server does)
        the motion's own control loop decelerates at its next step and returns False."""
        self.require_connected()
        if self._moving:
            self._stop_request = deceleration
            return
        self._decelerate(deceleration)

    def _decelerate(self, deceleration: float) -> None:
        q, qd = self.robot.arm_state()
        t_stop = float(np.abs(qd).max() / max(deceleration, 1e-6))
        q_stop = q + qd * t_stop / 2  # constant deceleration to rest
        self.robot.command_arm(q_stop, np.zeros(6))
        self.robot.world.step(max(1, int(np.ceil(t_stop / self.robot.world.config.time_step))))

    # internals -------------------------------------------------------------------------------
    def _before_motion(self) -> None:
        self.require_connected()
        if self._stopped:
            raise ProtectiveStopError("arm is in a protective stop; call unlockProtectiveStop() first")
        if self._teach:
            raise RuntimeError("arm is in teach mode (freedrive); call endTeachMode() before a motion")
        self._last_error = ""

    def _track(self, target, duration: float) -> bool:
        """Stream targets(t) -> (q, qd) at the physics rate; watch tracking error and contacts."""
        world = self.robot.world
        dt = world.config.time_step
        n = int(np.ceil(duration / dt)) + int(self.config.settle_time / dt)
        self.max_tracking_error = 0.0
        self._moving, self._stop_request = True, None
        try:
            return self._follow(target, duration, n, dt)
        finally:
            self._moving, self._stop_request = False, None

    def _follow(self, target, duration: float, n: int, dt: float) -> bool:
        world = self.robot.world
        for i in range(1, n + 1):
            if self._stop_request is not None:
                self._decelerate(self._stop_request)
                self._last_error = "stopped (stopJ)"
                return False
            try:
                q_des, qd_des = target(min(i * dt, duration))
            except _NoIK as exc:
                return self._halt(str(exc), protective=False)
            if i * dt > duration:
                qd_des = np.zeros(6)
            self.robot.command_arm(q_des, qd_des)
            world.step()
            errors = np.abs(self.robot.arm_state()[0] - q_des)  # (6,)
            error = float(errors.max())
            self.max_tracking_error = max(self.max_tracking_error, error)
            if error > self.config.tracking_error_limit:
                return self._halt(f"protective stop: tracking error {error:.3f} rad (joint {int(errors.argmax()) + 1})",
                                  protective=True)
            if i % 8 == 0 and (force := self._arm_contact_force()) > self.config.contact_force_limit:
                return self._halt(f"protective stop: {force:.0f} N contact on the arm", protective=True)
            if self._detecting and (change := self._force_change()) is not None:
                self._contact_detected = True
                return self._halt(f"contact detected: the force on the tool changed by {change:.0f} N",
                                  protective=False)
        return True

    def _force_change(self) -> float | None:
        """The change (N) of the tool's force since contact detection started, once it has stayed above
        the threshold for `contact_detection_time`; None before."""
        change = float(np.linalg.norm(self.getActualTCPForce()[:3] - self._force_zero))
        dt = self.robot.world.config.time_step
        window = max(1, round(self.config.contact_detection_time / dt))
        self._recent_changes = (self._recent_changes + [change])[-window:]
        if len(self._recent_changes) < window:
            return None
        held = min(self._recent_changes)  # N the change has stayed above over the window
        self.max_force_change = max(self.max_force_change, held)
        return change if held > self._detection_force else None

    def _halt(self, reason: str, protective: bool) -> bool:
        """End the motion at rest; `protective`: in a protective stop. Tells `on_stop` why."""
        self._last_error = reason
        self._stopped = self._stopped or protective
        for listener in self.on_stop:
            listener(reason)
        q = self.robot.arm_state()[0]
        self.robot.command_arm(q, np.zeros(6))
        self.robot.world.step(int(0.1 / self.robot.world.config.time_step))
        return False

    def _arm_contact_force(self) -> float:
        """Largest normal force on a moving arm link (not the fingers, not the base bolted to the
        table) from anything but the robot itself."""
        robot = self.robot
        worst = 0.0
        ignored = {-1, robot.links["base_link"], *robot.finger_links}
        for c in p.getContactPoints(bodyA=robot.body, physicsClientId=robot.client):
            if c[2] != robot.body and c[3] not in ignored:
                worst = max(worst, c[9])
        return worst


class _NoIK(RuntimeError):
    pass
