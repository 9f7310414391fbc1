"""Planning: IK round trips, Ruckig limits, straight Cartesian lines, the collision model."""
import numpy as np
import pytest

from app.motion.cartesian import line_path
from app.motion.ik import IKConfig, NoIKSolution, solve
from app.motion.scene import PlanningScene
from app.motion.trajectory import path_timing, through_waypoints
from app.se3 import line_length, make_pose, rotation_angle, rotvec_to_matrix
from hardware.interfaces import JointLimits
from hardware.kinematics import UR5Kinematics
from hardware.sim.arm import JOINT_ACCELERATION_LIMIT, JOINT_JERK_LIMIT
from hardware.sim.gripper_model import GripperGeometry
from hardware.sim.robot import HOME_Q


@pytest.fixture(scope="module")
def kin():
    return UR5Kinematics(GripperGeometry().T_tool0_tcp)


@pytest.fixture(scope="module")
def limits(kin):
    return JointLimits(kin.lower, kin.upper, kin.velocity_limit, JOINT_ACCELERATION_LIMIT, JOINT_JERK_LIMIT)


@pytest.fixture(scope="module")
def scene():
    s = PlanningScene()
    yield s
    s.close()


def test_ik_round_trip_on_100_random_reachable_poses(kin):
    rng = np.random.default_rng(0)
    config = IKConfig(random_seeds=6)
    for _ in range(100):
        q_true = rng.uniform(-np.pi, np.pi, 6)
        target = kin.fk(q_true)
        q = solve(kin, target, HOME_Q, None, config)
        reached = kin.fk(q)
        assert np.linalg.norm(reached[:3, 3] - target[:3, 3]) < 1e-4
        assert np.degrees(rotation_angle(reached[:3, :3].T @ target[:3, :3])) < 0.01


def test_ik_out_of_reach_and_colliding_poses_are_refused_with_reasons(kin, scene):
    far = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [1.5, 0.0, 0.2])
    with pytest.raises(NoIKSolution, match="out of reach"):
        solve(kin, far, HOME_Q, scene, IKConfig(random_seeds=4))
    below_table = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.5, 0.0, -0.05])
    with pytest.raises(NoIKSolution, match="collides .*table"):
        solve(kin, below_table, HOME_Q, scene, IKConfig(random_seeds=4))


def test_scene_flags_the_table_and_not_home(scene):
    assert scene.collisions(HOME_Q) == []
    down = HOME_Q.copy()
    down[1] = 0.3  # upper arm pointing into the table
    assert any(hit.endswith("-table") for hit in scene.collisions(down))


def test_chained_ruckig_segments_respect_limits_and_rest_at_waypoints(limits):
    rng = np.random.default_rng(1)
    waypoints = [HOME_Q + rng.uniform(-1.0, 1.0, 6) for _ in range(4)]
    traj = through_waypoints(waypoints, limits, speed=10.0, acceleration=100.0)  # the limits bind
    dt = np.diff(traj.times)
    qdd = np.diff(traj.qd, axis=0) / dt[:, None]
    assert np.all(np.abs(traj.qd) <= limits.velocity * (1 + 1e-6))
    assert np.all(np.abs(qdd) <= limits.acceleration * 1.02)
    assert np.allclose(traj.q[0], waypoints[0]) and np.allclose(traj.end, waypoints[-1], atol=1e-9)
    assert np.allclose(traj.qd[[0, -1]], 0.0, atol=1e-9)
    for w in waypoints[1:-1]:  # the chain stops at every waypoint
        i = np.argmin(np.abs(traj.q - w).max(axis=1))
        assert np.abs(traj.q[i] - w).max() < 1e-9 and np.abs(traj.qd[i]).max() < 1e-9


def test_cartesian_approach_stays_on_the_straight_line(kin, limits, scene):
    T_grasp = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.5, 0.05, 0.12])
    q_grasp = solve(kin, T_grasp, HOME_Q, scene)
    T_pre = T_grasp @ make_pose(t=[0.0, 0.0, -0.10])
    path = line_path(kin, T_grasp, T_pre, q_grasp, scene)
    traj = path_timing(path, line_length(T_grasp, T_pre), limits, 0.15, 0.6, 5.0)
    a, b = T_grasp[:3, 3], T_pre[:3, 3]
    u = (b - a) / np.linalg.norm(b - a)
    for q in traj.q:
        p = kin.fk(q)[:3, 3]
        off_line = np.linalg.norm((p - a) - ((p - a) @ u) * u)
        assert off_line < 0.002
    assert np.all(np.abs(traj.qd) <= limits.velocity)
    speeds = np.linalg.norm(np.diff([kin.fk(q)[:3, 3] for q in traj.q], axis=0), axis=1) / np.diff(traj.times)
    assert speeds.max() <= 0.15 * 1.05
    assert np.allclose(kin.fk(traj.end), T_pre, atol=1e-4)
