"""Timing within the joints' limits: the carry's (`Planner._carry_profile`: an object held near its
centroid has its wrist joints moved at `carry_wrist_*`, the others at the carry's speed; one held far
from it, every joint at the carry's speed) and a straight line's near the wrist's singularity
(`path_timing`, whose joint path bends sharply)."""
import numpy as np
import pytest

from app.motion.cartesian import line_path
from app.motion.config import MotionConfig
from app.motion.planner import Planner
from app.motion.scene import PlanningScene
from app.motion.trajectory import path_timing, remainder
from hardware.gripper_geometry import GripperGeometry
from hardware.interfaces import JointLimits
from hardware.kinematics import UR5Kinematics
from hardware.robot_description import HOME_Q
from hardware.se3 import line_length, make_pose
from hardware.sim.arm import JOINT_ACCELERATION_LIMIT, JOINT_JERK_LIMIT


@pytest.fixture(scope="module")
def planner():
    kin = UR5Kinematics(GripperGeometry().T_tool0_tcp)
    limits = JointLimits(kin.lower, kin.upper, kin.velocity_limit, JOINT_ACCELERATION_LIMIT, JOINT_JERK_LIMIT)
    scene = PlanningScene()
    yield Planner(kin, limits, scene)
    scene.close()


def test_a_carry_held_near_its_centroid_turns_its_wrist_at_the_wrist_speed_and_no_other_joint_faster(planner):
    """Half a turn of the wrist with a little of the base (the tool pointing down throughout, so no pivot
    about the fingers' axis): held at a mug's rim (lever 4 cm) the wrist reaches beyond the carry's
    1.05 rad/s, up to its 2.0, and the base stays within 1.05; held 10 cm off (a bottle at its neck)
    every joint stays within 1.05 and the carry takes longer by the wrist's time."""
    c = MotionConfig()
    q0 = np.asarray(HOME_Q, float)
    q1 = q0 + [0.3, 0.0, 0.0, 0.0, 0.0, np.pi]
    assert not planner.scene.collisions(q0) and not planner.scene.collisions(q1)
    near, _ = planner.carry(q0, q1, lever=0.04)
    far, _ = planner.carry(q0, q1, lever=0.10)
    for traj in (near, far):
        assert np.allclose(traj.q[0], q0) and np.allclose(traj.q[-1], q1, atol=1e-6)
    peak_near, peak_far = np.abs(near.qd).max(axis=0), np.abs(far.qd).max(axis=0)  # (6,)
    assert peak_near[:3].max() <= c.carry_speed + 1e-6 and peak_near[3:].max() <= c.carry_wrist_speed + 1e-6
    assert peak_near[5] > 1.5 * c.carry_speed
    assert peak_far.max() <= c.carry_speed + 1e-6
    # pi at 2.0 rad/s and 4.0 rad/s^2: 2.07 s (jerk-limited a little more); at 1.05 and 1.4: 3.74 s
    assert near.duration < 2.4 and far.duration > 3.7
    assert np.abs(np.diff(near.qd, axis=0) / np.diff(near.times)[:, None])[:, 3:].max() <= c.carry_wrist_acceleration + 1e-3


def _peaks(traj) -> tuple[np.ndarray, np.ndarray]:
    """(6,) each joint's peak speed and peak acceleration (from the sampled velocities) over a trajectory."""
    qdd = np.diff(traj.qd, axis=0) / np.diff(traj.times)[:, None]
    return np.abs(traj.qd).max(axis=0), np.abs(qdd).max(axis=0)


def test_a_line_near_the_wrist_singularity_is_timed_within_every_joints_limits(planner):
    """A hung mug's retreat with the wrist near its singularity (q5 ~ 0.1): the wrist turns 2 rad over
    the 10 cm line, so the joint path bends sharply; timed at the free lines' 0.25 m/s, its joints stay
    within their speed and acceleration limits (the bend's term q'' (ds/dt)^2 taken in), and so does
    the rest of it timed again from where a contact stopped the arm halfway (`remainder`)."""
    kin, limits = planner.kin, planner.limits
    q_hang = np.array([3.293, -1.2, 2.106, -3.054, -0.109, -0.201])
    T0 = kin.fk(q_hang)
    T1 = T0 @ make_pose(t=[0.0, 0.0, -0.10])
    path = line_path(kin, T0, T1, q_hang)
    bend = np.abs(np.diff(path, 2, axis=0)).max() / (0.10 / (len(path) - 1)) ** 2
    assert bend > 200  # rad/m^2: at 0.25 m/s that term alone would ask > 12 rad/s^2 of a wrist joint
    line = path_timing(path, line_length(T0, T1), limits, 0.25, 1.2, 20.0, "retreat")
    rest = remainder(line, line.q[len(line.q) // 2], limits)
    for traj in (line, rest):
        speed, acceleration = _peaks(traj)
        assert np.all(speed <= limits.velocity * 1.01) and np.all(acceleration <= limits.acceleration * 1.05), (
            speed.round(2), acceleration.round(1))
    assert np.allclose(rest.q[-1], line.q[-1]) and np.allclose(rest.q[0], line.q[len(line.q) // 2])
