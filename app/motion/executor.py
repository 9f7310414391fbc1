"""Running planned motions on the arm (`app.motion.planner` plans them): a trajectory through `Arm`,
and the typed failure when it does not complete (`app.failures.ExecutionFailure`)."""
from __future__ import annotations

import numpy as np

from app.failures import ExecutionFailure, MotionStopped, ProtectiveStop
from app.motion.trajectory import JointTrajectory
from hardware.interfaces import Arm

START_GAP = 0.01  # rad: a trajectory the arm's drivers run must start this close to its joints


def back_to_start(arm: Arm, traj: JointTrajectory, tolerance: float = 0.02, speed: float = 0.5) -> None:
    """Bring an arm that stands farther than `tolerance` from a trajectory's start back there with a
    short moveJ (the gripper opening on a held object can push the wrist off the planned place);
    ExecutionFailure when that motion stops. Closer than `tolerance`, `execute` starts from where it stands."""
    if float(np.abs(arm.getActualQ() - traj.q[0]).max()) > tolerance and not arm.moveJ(traj.q[0], speed, 2 * speed):
        raise motion_failure(arm, f"{traj.label}: returning to its start")


def execute(arm: Arm, traj: JointTrajectory, tolerance: float = 0.02) -> None:
    """Run a planned trajectory on the arm; ExecutionFailure on a stop or if it ends off target. An arm
    that the last segment left within `tolerance` of this one's start but not within START_GAP (the
    drivers refuse a path that does not start where the arm is; a loaded arm sags that far) starts
    the path from where it stands: its first sample becomes the arm's joints."""
    q_now = arm.getActualQ()
    if START_GAP < float(np.abs(q_now - traj.q[0]).max()) <= tolerance:
        q = traj.q.copy()
        q[0] = q_now
        traj = JointTrajectory(traj.times, q, traj.qd, traj.label)
    if not arm.executeTrajectory(traj.times, traj.q, traj.qd):
        raise motion_failure(arm, traj.label, stopped="")
    error = float(np.abs(arm.getActualQ() - traj.end).max())
    if error > tolerance:
        raise MotionStopped(f"{traj.label}: ended {error:.3f} rad from its target")


def motion_failure(arm: Arm, what: str, stopped: str = " stopped") -> ExecutionFailure:
    """The failure of a motion `what` the arm did not complete: ProtectiveStop while the arm is in one,
    MotionStopped otherwise; the message says what, and the arm's own reason."""
    why = f"{what}{stopped}: {arm.getLastError() or 'motion stopped'}"
    return ProtectiveStop(why) if arm.isProtectiveStopped() else MotionStopped(why)
