"""The carry's timing (`Planner._carry_profile`): an object held near its centroid has its wrist joints
moved at `carry_wrist_*`, the others at the carry's speed; one held far from it, every joint at the
carry's speed."""
import numpy as np
import pytest

from app.motion.config import MotionConfig
from app.motion.planner import Planner
from app.motion.scene import PlanningScene
from hardware.gripper_geometry import GripperGeometry
from hardware.interfaces import JointLimits
from hardware.kinematics import UR5Kinematics
from hardware.robot_description import HOME_Q
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
