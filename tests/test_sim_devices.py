import numpy as np
import pytest

from hardware.interfaces import DeviceNotConnectedError, ProtectiveStopError
from hardware.robot_description import HOME_Q
from hardware.sim.arm import SimArm, SimArmConfig
from hardware.sim.gripper import SimGripper, SimGripperConfig
from hardware.sim.robot import SimRobot
from hardware.sim.world import SimWorld


@pytest.fixture
def rig():
    world = SimWorld()
    robot = SimRobot(world)
    arm, gripper = SimArm(SimArmConfig(), robot), SimGripper(SimGripperConfig(), robot)
    with world, arm, gripper:
        yield world, robot, arm, gripper


def record_steps(world, fn):
    """From now on, append fn() to the returned list after every physics step."""
    samples = []
    step = world.step

    def probing_step(n=1):
        step(n)
        samples.append(fn())

    world.step = probing_step
    return samples


def test_devices_refuse_use_while_disconnected():
    world = SimWorld()
    arm = SimArm(SimArmConfig(), SimRobot(world))
    with pytest.raises(DeviceNotConnectedError, match="not connected"):
        arm.getActualQ()
    arm.connect()
    arm.connect()  # idempotent
    assert np.allclose(arm.getActualQ(), HOME_Q, atol=1e-6)
    arm.disconnect()
    arm.disconnect()
    with pytest.raises(DeviceNotConnectedError):
        arm.moveJ(HOME_Q)
    world.disconnect()


def test_pybullet_and_pinocchio_forward_kinematics_agree(rig, rng):
    world, robot, arm, _ = rig
    for q in rng.uniform(-np.pi, np.pi, size=(20, 6)):
        robot.reset_arm(q)
        for frame in ("tool0", "wrist_2_link", "forearm_link"):
            T_sim, T_pin = robot.link_pose(frame), robot.kinematics.frame_pose(q, frame)
            assert np.abs(T_sim[:3, 3] - T_pin[:3, 3]).max() < 1e-6
            assert np.abs(T_sim[:3, :3] - T_pin[:3, :3]).max() < 1e-6


def test_moveJ_reaches_target_within_speed_limits(rig):
    world, robot, arm, _ = rig
    target = HOME_Q + np.array([0.6, 0.3, -0.4, 0.5, 0.4, 1.2])
    speeds = record_steps(world, arm.getActualQd)
    assert arm.moveJ(target, speed=2.0, acceleration=4.0), arm.getLastError()
    assert np.abs(arm.getActualQ() - target).max() < 1e-3
    assert np.abs(np.array(speeds)).max() <= 2.0 * 1.02  # the commanded speed, 2 % tracking slack
    with pytest.raises(ValueError, match="outside the joint limits"):
        arm.moveJ(np.array([0, 0, 4.0, 0, 0, 0]))


def test_moveL_stays_on_the_line(rig):
    world, robot, arm, _ = rig
    start = arm.getActualTCPPose()
    goal = start.copy()
    goal[:3] += [0.12, -0.08, -0.10]
    path = record_steps(world, lambda: arm.getActualTCPPose()[:3])
    assert arm.moveL(goal, speed=0.2), arm.getLastError()
    assert np.abs(arm.getActualTCPPose()[:3] - goal[:3]).max() < 1e-3
    d = (goal[:3] - start[:3]) / np.linalg.norm(goal[:3] - start[:3])
    offsets = np.array(path) - start[:3]
    off_line = np.linalg.norm(offsets - (offsets @ d)[:, None] * d, axis=1)
    assert off_line.max() < 0.002


def test_protective_stop_on_collision_with_the_table(rig):
    world, robot, arm, _ = rig
    below_table = arm.getActualTCPPose()
    below_table[2] = -0.2
    assert not arm.moveL(below_table, speed=0.2)
    assert arm.isProtectiveStopped() and "protective stop" in arm.getLastError()
    assert arm.getActualTCPPose()[2] > -0.02  # it stopped at the table
    with pytest.raises(ProtectiveStopError):
        arm.moveJ(HOME_Q)
    arm.unlockProtectiveStop()
    assert arm.moveJ(HOME_Q)


def test_contact_detection_ends_a_motion_at_rest_without_a_protective_stop(rig):
    """The same line into the table as above, under contact detection: the tool meets the table, the
    arm stops there unlocked, and moves again at once."""
    world, robot, arm, _ = rig
    below_table = arm.getActualTCPPose()
    below_table[2] = -0.2
    assert arm.startContactDetection() and not arm.readContactDetection()
    assert not arm.moveL(below_table, speed=0.2)
    assert not arm.isProtectiveStopped() and "contact detected" in arm.getLastError()
    assert arm.readContactDetection()
    assert -0.02 < arm.getActualTCPPose()[2] < 0.05  # at the table, the fingers on it
    assert np.linalg.norm(arm.getActualQd()) < 0.05
    assert arm.stopContactDetection() and not arm.readContactDetection()
    assert arm.moveJ(HOME_Q), arm.getLastError()


def test_the_wrist_reads_a_held_boxs_weight(rig):
    """Nothing touched: no wrench. A 0.5 kg box held at the TCP: the squeeze cancels between the pads,
    the force is its weight, straight down, and about the TCP (the box's centre on the tool's axis) no torque."""
    from hardware.bullet import p
    from hardware.se3 import ur_to_pose

    world, robot, arm, gripper = rig
    assert np.allclose(arm.getActualTCPForce(), 0.0)
    T = ur_to_pose(arm.getActualTCPPose())
    box = world.add_box((0.03, 0.03, 0.03), T[:3, 3] + T[:3, :3] @ [0.0, 0.0, 0.01])  # static while closing
    assert gripper.close(force=30.0)
    p.changeDynamics(box, -1, mass=0.5, physicsClientId=robot.client)
    world.step(240)
    wrench = arm.getActualTCPForce()
    assert np.allclose(wrench[:3], [0.0, 0.0, -0.5 * 9.81], atol=0.05), wrench
    assert np.abs(wrench[3:]).max() < 0.01, wrench


def test_gripper_closes_on_nothing_and_opens(rig):
    _, _, _, gripper = rig
    assert np.isclose(gripper.width, gripper.stroke, atol=1e-3)
    assert gripper.close(force=30.0) is False and not gripper.object_detected
    assert gripper.width < 0.002
    gripper.open(width=0.03)  # a partial opening, as jobs let go of an object
    assert np.isclose(gripper.width, 0.03, atol=1e-3)
    gripper.open()
    assert np.isclose(gripper.width, gripper.stroke, atol=1e-3)
    with pytest.raises(ValueError, match="grip force"):
        gripper.close(force=500.0)
    with pytest.raises(ValueError, match="gripper opening"):
        gripper.open(width=0.2)


def test_a_held_object_that_goes_is_no_longer_detected(rig):
    """Closed on a 3 cm box between the pads: detected; the box gone, the fingers run on to closed and
    object_detected says so at once (a Robotiq's live object status), with no new command."""
    from hardware.se3 import ur_to_pose

    world, _, arm, gripper = rig
    T = ur_to_pose(arm.getActualTCPPose())
    assert gripper.force < 1.0  # open: the motors hold nothing
    box = world.add_box((0.03, 0.03, 0.03), T[:3, 3] + T[:3, :3] @ [0.0, 0.0, 0.01])
    assert gripper.close(force=30.0) and gripper.object_detected
    assert abs(gripper.width - 0.03) < 0.004
    gripper.close(force=10.0)
    assert gripper.force == pytest.approx(10.0, abs=0.5)  # squeezing the box at the force asked
    gripper.close(force=20.0)
    assert gripper.force == pytest.approx(20.0, abs=0.5)
    world.remove(box)
    world.step(240)
    assert gripper.width < 0.002 and not gripper.object_detected


UR5_DH = {"d": [0.089159, 0, 0, 0.10915, 0.09465, 0.0823], "a": [0, -0.425, -0.39225, 0, 0, 0],
          "alpha": [np.pi / 2, 0, 0, np.pi / 2, -np.pi / 2, 0]}  # Universal Robots' published UR5 parameters


def ur5_dh_fk(q: np.ndarray) -> np.ndarray:
    """base -> tool0 from the standard DH table: independent of Pinocchio and of the URDF."""
    T = np.eye(4)
    for qi, d, a, alpha in zip(q, UR5_DH["d"], UR5_DH["a"], UR5_DH["alpha"]):
        ct, st, ca, sa = np.cos(qi), np.sin(qi), np.cos(alpha), np.sin(alpha)
        T = T @ np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]])
    return T


def test_tcp_pose_matches_ur_convention(rig):
    from scipy.spatial.transform import Rotation

    _, robot, arm, _ = rig
    # UR5 at zero joints: tool0 at (a2 + a3, -(d4 + d6), d1 - d5), the arm stretched out along -x
    assert np.allclose(robot.kinematics.fk(np.zeros(6))[:3, 3] - robot.kinematics.fk(np.zeros(6))[:3, :3]
                       @ [0, 0, robot.geometry.tcp_z], [-0.81725, -0.19145, -0.005491], atol=1e-5)
    q = arm.getActualQ()
    expected = ur5_dh_fk(q)
    expected[:3, 3] += expected[:3, :3] @ [0, 0, 0.100]  # the TCP 0.100 m along tool0's z (our gripper)
    pose = np.asarray(arm.getActualTCPPose())
    assert np.allclose(pose[:3], expected[:3, 3], atol=1e-5)
    assert np.allclose(Rotation.from_rotvec(pose[3:]).as_matrix(), expected[:3, :3], atol=1e-5)
    assert np.allclose(arm.getTCPOffset()[:3], [0, 0, 0.100])


def test_stepping_is_deterministic():
    import numpy as np

    from app.simcell.cell import SimCell
    from app.simcell.spawn import spawn

    def run_once():
        with SimCell() as cell:
            obj = spawn(cell.world, "bottle", 100_002, "upright", rng=np.random.default_rng(5))
            cell.arm.moveJ(HOME_Q + 0.3)
            cell.world.step(120)
            return np.concatenate([cell.arm.getActualQ(), cell.world.pose(obj.body).ravel()]), cell.camera.capture().depth

    (state_a, depth_a), (state_b, depth_b) = run_once(), run_once()
    assert np.array_equal(state_a, state_b) and np.array_equal(depth_a, depth_b)


def test_execute_trajectory_and_stop(rig):
    import pybullet as p

    world, robot, arm, _ = rig
    q0 = arm.getActualQ()
    times = np.linspace(0.0, 2.0, 41)
    s = (1 - np.cos(np.pi * times / 2.0)) / 2  # rest to rest
    q = q0 + s[:, None] * np.array([0.4, 0.2, -0.2, 0.3, 0.2, 0.5])
    assert arm.executeTrajectory(times, q), arm.getLastError()
    assert np.abs(arm.getActualQ() - q[-1]).max() < 2e-3
    with pytest.raises(ValueError, match="does not start"):
        arm.executeTrajectory(times, q + 0.1)
    with pytest.raises(ValueError, match="increasing times"):
        arm.executeTrajectory(times[::-1], q)
    # a moving arm brought to rest by stopJ
    for j, qd in zip(robot.arm_joints, [0.8, -0.5, 0.4, 0.0, 0.0, 0.6]):
        p.resetJointState(robot.body, j, p.getJointState(robot.body, j, physicsClientId=robot.client)[0], qd,
                          physicsClientId=robot.client)
    arm.stopJ(deceleration=4.0)
    world.step(24)
    assert np.abs(arm.getActualQd()).max() < 0.01
