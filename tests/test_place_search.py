"""The place line under contact detection, its search aside and the guarded way out (app.jobs.guarded), on the
simulated arm."""
from types import SimpleNamespace

import numpy as np
import pytest

from app.failures import ContactStop, ProtectiveStop
from app.jobs.guarded import PLACE_ARRIVED, SEARCH_RINGS, guarded_leave, search_offsets, search_place
from app.motion.trajectory import joint_segment
from hardware.kinematics import UR5Kinematics
from hardware.robot_description import HOME_Q
from hardware.se3 import make_pose, pose_to_ur, ur_to_pose
from hardware.sim.arm import SimArm, SimArmConfig
from hardware.sim.gripper import SimGripper, SimGripperConfig
from hardware.sim.robot import SimRobot
from hardware.sim.world import SimWorld


def test_the_search_offsets_lie_across_the_line_on_their_rings():
    direction = np.array([0.3, -0.5, 0.8])
    offsets = np.array(search_offsets(direction))  # (K, 3)
    assert len(offsets) == sum(n for _, n in SEARCH_RINGS)
    assert np.abs(offsets @ direction).max() < 1e-12
    radii = np.linalg.norm(offsets, axis=1)
    expected = np.concatenate([[r] * n for r, n in SEARCH_RINGS])
    np.testing.assert_allclose(radii, expected, atol=1e-12)
    first = offsets[: SEARCH_RINGS[0][1]]
    np.testing.assert_allclose(first.mean(axis=0), 0.0, atol=1e-12)  # evenly around the line


@pytest.fixture
def job(monkeypatch):
    """The pieces of a job the search uses: the simulated arm with its fingers closed, its kinematics.
    Slower lines than a job's: closed fingers on a rigid post, not a mug that gives in the grasp."""
    monkeypatch.setattr("app.jobs.guarded.SEARCH_SPEED", SLOW)
    world = SimWorld()
    robot = SimRobot(world)
    arm, gripper = SimArm(SimArmConfig(), robot), SimGripper(SimGripperConfig(), robot)
    with world, arm, gripper:
        assert arm.moveJ(HOME_Q)
        gripper.close()
        kin = UR5Kinematics(tcp_offset=ur_to_pose(arm.getTCPOffset()))
        yield SimpleNamespace(arm=arm, kin=kin, world=world, config=SimpleNamespace(place_contact_force=30.0),
                              result=SimpleNamespace(notes=[]))


SLOW = 0.03  # m/s


def _line_down(job, z_pre: float = 0.20, length: float = 0.10):
    """A pre-place above the table and a place `length` straight down from it, the tool as at home."""
    T0 = ur_to_pose(job.arm.getActualTCPPose())
    T_pre = make_pose(T0[:3, :3], [T0[0, 3], T0[1, 3], z_pre])
    return T_pre, make_pose(T0[:3, :3], [T0[0, 3], T0[1, 3], z_pre - length])


def test_a_line_blocked_by_a_post_is_found_beside_it(job):
    T_pre, T_place = _line_down(job)
    u = search_offsets(T_place[:3, 3] - T_pre[:3, 3])[0] / SEARCH_RINGS[0][0]  # unit, across the line
    post = T_place[:3, 3] + 0.008 * u  # a 1 cm post 8 mm off the line, its top 5 cm above the place
    job.world.add_box((0.01, 0.01, 0.15), [post[0], post[1], 0.075])
    assert job.arm.moveL(pose_to_ur(T_pre), 0.1)
    job.arm.startContactDetection(30.0)
    assert not job.arm.moveL(pose_to_ur(T_place), SLOW) and job.arm.readContactDetection()  # the nominal line is blocked
    job.arm.stopContactDetection()
    short = search_place(job, T_pre, T_place, 0.05, "a contact")
    assert short <= PLACE_ARRIVED and not job.arm.isProtectiveStopped()
    at = ur_to_pose(job.arm.getActualTCPPose())[:3, 3]
    aside = at - T_place[:3, 3]
    assert np.linalg.norm(aside[:2]) > SEARCH_RINGS[0][0] - 1e-3  # not on the nominal line
    assert np.dot(aside[:2], u[:2]) < 0  # away from the post
    assert any("met something" in note for note in job.result.notes)  # lines nearer the post were stopped


def test_a_place_blocked_on_every_line_fails_at_rest_at_the_pre_place(job):
    T_pre, T_place = _line_down(job, z_pre=0.12, length=0.06)
    job.world.add_box((0.2, 0.2, 0.08), [T_place[0, 3], T_place[1, 3], 0.04])  # a block under all the lines
    assert job.arm.moveL(pose_to_ur(T_pre), 0.1)
    with pytest.raises(ContactStop, match="on each of"):
        search_place(job, T_pre, T_place, 0.05, "a contact")
    assert not job.arm.isProtectiveStopped()
    assert np.linalg.norm(ur_to_pose(job.arm.getActualTCPPose())[:3, 3] - T_pre[:3, 3]) < 0.002
    assert len(job.result.notes) == sum(n for _, n in SEARCH_RINGS)


@pytest.mark.parametrize("name", ["approach_contact_force", "place_contact_force"])
def test_a_contact_force_that_is_not_positive_is_refused_by_name(name):
    from app.jobs.settings import JobConfig

    with pytest.raises(ValueError, match=rf"^{name} must be in \(0, "):
        JobConfig(**{name: 0.0})


@pytest.mark.parametrize("guarded", [True, False])
def test_a_way_out_that_meets_something_stops_opens_fully_and_carries_on(guarded):
    """A retreat 10 cm along the base's +y runs a finger (fingers 40 mm apart) into a bar that fully open
    fingers straddle (the hung mug swinging into a finger). Guarded, the arm stops at rest, the gripper
    opens fully and the arm carries on along the retreat and home as planned; unguarded, the same
    retreat ends in a protective stop."""
    world = SimWorld()
    robot = SimRobot(world)
    arm, gripper = SimArm(SimArmConfig(), robot), SimGripper(SimGripperConfig(), robot)
    with world, arm, gripper:
        assert arm.moveJ(HOME_Q)
        gripper.open(width=0.04)
        kin = UR5Kinematics(tcp_offset=ur_to_pose(arm.getTCPOffset()))
        T0, q0 = ur_to_pose(arm.getActualTCPPose()), arm.getActualQ()
        aside = T0.copy()
        aside[1, 3] += 0.10
        retreat = joint_segment(q0, kin.ik_nearest(aside, q0), arm.joint_limits, 0.05, 0.5, "retreat")  # slow: rigid
        home = joint_segment(retreat.end, q0, arm.joint_limits, 0.3, 1.0, "home")
        bar = T0[:3, 3] + 0.025 * T0[:3, 1] + [0.0, 0.07, 0.01]  # 14-36 mm along the fingers' axis, below the palm:
        world.add_box((0.022, 0.02, 0.03), bar)  # a finger 20-32 mm out meets it, both 42-55 mm out straddle it
        config = SimpleNamespace(leave_contact_force=30.0, motion=SimpleNamespace(end_tolerance=0.02))
        job = SimpleNamespace(arm=arm, gripper=gripper, kin=kin, guards_hang=lambda: guarded, config=config,
                              result=SimpleNamespace(notes=[]))
        if not guarded:
            with pytest.raises(ProtectiveStop, match="protective stop"):
                guarded_leave(job, [retreat, home])
            return
        guarded_leave(job, [retreat, home])
        assert not arm.isProtectiveStopped()
        assert gripper.width == pytest.approx(gripper.stroke, abs=2e-3)
        np.testing.assert_allclose(arm.getActualQ(), q0, atol=0.02)  # the retreat, then home, as planned
        assert len(job.result.notes) == 1 and "opened fully" in job.result.notes[0]
