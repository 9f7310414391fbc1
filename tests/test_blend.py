"""Blended joint paths (`app.motion.blend`): through waypoints without a stop at each, within the
velocity, acceleration and jerk limits, and passed at rest where the blend would cut into something."""
from __future__ import annotations

import numpy as np
import pytest

from app.motion.blend import blend_checked, blended, via_velocities
from app.motion.trajectory import JointTrajectory, through_waypoints
from hardware.interfaces import JointLimits
from hardware.kinematics import UR5Kinematics
from hardware.robot_description import HOME_Q
from hardware.sim.arm import JOINT_ACCELERATION_LIMIT, JOINT_JERK_LIMIT

SPEED, ACCELERATION = 2.0, 4.0


@pytest.fixture(scope="module")
def limits():
    k = UR5Kinematics()
    return JointLimits(k.lower, k.upper, k.velocity_limit, JOINT_ACCELERATION_LIMIT, JOINT_JERK_LIMIT)


def assert_within_limits(traj: JointTrajectory, limits: JointLimits) -> None:
    """Velocities and accelerations within the caps asked; jerk, the accelerations' slope between
    samples (a mean of the piecewise-constant jerk), within the joints' jerk limits."""
    v_cap, a_cap = np.minimum(SPEED, limits.velocity), np.minimum(ACCELERATION, limits.acceleration)
    assert (np.abs(traj.qd) <= v_cap + 1e-6).all()
    assert (np.abs(traj.qdd) <= a_cap + 1e-6).all()
    jerk = np.abs(np.diff(traj.qdd, axis=0)) / np.diff(traj.times)[:, None]  # (T-1, D)
    assert (jerk <= limits.jerk * (1 + 1e-6) + 1e-6).all()


def passes_each(traj: JointTrajectory, waypoints: np.ndarray) -> bool:
    return all(np.abs(traj.q - w).max(axis=1).min() < 1e-9 for w in waypoints)


def test_a_path_that_keeps_its_direction_runs_through_its_waypoints_without_stopping(limits):
    """Nine points on one joint-space line: the blend passes each, never at rest between the ends,
    within the limits, and takes far less time than the chain that stops at each."""
    waypoints = HOME_Q + np.linspace(0.0, 1.0, 9)[:, None] * np.array([1.6, 0.8, 0.4, 0.0, 0.0, 1.0])
    traj, passes = blended(waypoints, limits, SPEED, ACCELERATION)
    chain = through_waypoints(list(waypoints), limits, SPEED, ACCELERATION)
    assert passes_each(traj, waypoints) and np.allclose(traj.q[-1], waypoints[-1])
    between = (traj.times >= passes[1]) & (traj.times <= passes[-2])  # from the second waypoint to the last but one
    assert np.abs(traj.qd[between]).max(axis=1).min() > 0.5  # never at rest on the way
    assert traj.duration < 0.75 * chain.duration
    assert_within_limits(traj, limits)
    assert len(passes) == len(waypoints) and np.isclose(passes[-1], traj.duration)


def test_a_joint_that_turns_back_at_a_waypoint_passes_it_at_rest():
    """The via velocity: zero on a joint whose motion changes sign there, and at most twice the slower
    of the two segments' mean speeds where it keeps its direction (the module's rule)."""
    waypoints = np.array([[0.0, 0.0], [1.0, 0.5], [2.0, 0.0]])
    v = via_velocities(waypoints, np.array([1.0, 2.0]), np.array([3.0, 3.0]))
    assert np.allclose(v[[0, 2]], 0.0) and v[1, 1] == 0.0 and np.isclose(v[1, 0], 1.0)  # 2 x min(1/1, 1/2)
    assert np.allclose(via_velocities(waypoints, np.array([1.0, 2.0]), np.array([0.4, 3.0]))[1], [0.4, 0.0])
    assert np.allclose(via_velocities(waypoints, np.array([1.0, 2.0]), np.array([3.0, 3.0]), frozenset({1})), 0.0)


def test_a_blend_that_would_cut_a_corner_into_an_obstacle_passes_that_corner_at_rest(limits):
    """A corner with an obstacle just beside it (a box in joint space, clear of the straight segments,
    where the blend swings wide before the corner): the unchecked blend cuts into it; the checked one passes the corner at rest on the straight
    segments, and still blends the next waypoint, so it is quicker than the chain that stops at each."""
    corner = np.array([1.0, 0.2])
    plane = np.array([[0.0, 0.0], corner, [1.2, 1.2], [1.4, 2.2]])  # joints 0 and 1; the rest still
    waypoints = np.tile(HOME_Q, (4, 1))
    waypoints[:, :2] += plane

    def inside(q: np.ndarray) -> bool:
        d = q[:2] - HOME_Q[:2]
        return bool(0.85 <= d[0] <= 0.95 and 0.13 <= d[1] <= 0.16)

    assert not any(inside(w) for w in waypoints)
    assert not any(inside(a + s * (b - a)) for a, b in zip(waypoints[:-1], waypoints[1:]) for s in np.linspace(0, 1, 500))

    def first_bad(traj: JointTrajectory) -> float | None:
        return next((float(t) for t, q in zip(traj.times, traj.q) if inside(q)), None)

    naive, _ = blended(waypoints, limits, SPEED, ACCELERATION)
    assert first_bad(naive) is not None  # the case is real: a naive blend cuts the corner
    traj = blend_checked(waypoints, limits, SPEED, ACCELERATION, "around", first_bad)
    assert first_bad(traj) is None and passes_each(traj, waypoints)
    i = int(np.abs(traj.q - waypoints[1]).max(axis=1).argmin())
    assert np.abs(traj.qd[i]).max() < 1e-9  # at rest at the corner
    assert traj.duration < through_waypoints(list(waypoints), limits, SPEED, ACCELERATION).duration - 0.1
    assert_within_limits(traj, limits)


def test_a_blended_transit_around_an_obstacle_is_free_at_every_sample_and_quicker(limits, monkeypatch):
    """The planner's transit around a pillar in the planning scene (a sampled path): collision-free at every
    4 ms sample, within the limits, and no slower than the same waypoints timed with a stop at each."""
    from dataclasses import replace

    from app.motion import planner as planning
    from app.motion.planner import Planner
    from app.motion.scene import PlanningScene
    from tests.test_motion import _pillar_between_two_reaches

    kin = UR5Kinematics()
    q0, q1, pillar = _pillar_between_two_reaches(kin)
    scene = PlanningScene()
    try:
        scene.add_cloud("pillar", pillar)
        seen, original = [], planning.plan_joint_path
        monkeypatch.setattr(planning, "plan_joint_path", lambda *a, **k: seen.append(original(*a, **k)) or seen[-1])
        planner = Planner(kin, limits, scene)
        traj = planner.transit(q0, q1, "around")
        assert seen and len(seen[0]) >= 3  # it went through the sampling planner's waypoints
        assert not any(scene.collisions(q) for q in traj.q)
        assert np.allclose(traj.q[0], q0) and np.allclose(traj.end, q1, atol=1e-9)
        v_cap = np.minimum(planner.config.joint_speed, limits.velocity)
        assert (np.abs(traj.qd) <= v_cap + 1e-6).all()
        stops = Planner(kin, limits, scene, replace(planner.config, blend=False))
        assert traj.duration <= stops._timed(seen[0], "around").duration + 1e-9
    finally:
        scene.close()


def test_a_straight_segment_stays_on_it_where_ruckigs_phase_synchronisation_falls_back(limits):
    """A rest-to-rest motion asked to be straight: Ruckig's phase synchronisation finds no such profile for
    these two configurations and leaves the segment by 0.036 rad; `joint_segment(straight=True)` keeps to
    it exactly (a 1-D profile along it), in the same time, within the limits."""
    from ruckig import InputParameter, Ruckig, Synchronization, Trajectory

    from app.motion.trajectory import joint_segment, sample_states

    q0 = np.array([0.066, -0.017, -1.538, 1.952, -0.4, 2.073])
    q1 = np.array([0.019, 0.867, -1.616, 2.006, -1.36, 1.545])
    d = q1 - q0

    def off(q: np.ndarray) -> float:
        s = (q - q0) @ d / (d @ d)  # (T,)
        return float(np.abs(q0 + s[:, None] * d - q).max())

    v, a = np.minimum(SPEED, limits.velocity), np.minimum(ACCELERATION, limits.acceleration)
    inp = InputParameter(6)  # Ruckig asked for phase synchronisation, at rest at both ends
    inp.current_position, inp.target_position = list(q0), list(q1)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = list(v), list(a), list(limits.jerk)
    inp.synchronization = Synchronization.Phase
    ruckig = Trajectory(6)
    Ruckig(6).calculate(inp, ruckig)
    assert off(sample_states(ruckig)[1]) > 0.03  # the case is real
    traj = joint_segment(q0, q1, limits, SPEED, ACCELERATION, straight=True)
    assert off(traj.q) < 1e-9 and np.allclose(traj.q[[0, -1]], [q0, q1], atol=1e-12)
    assert abs(traj.duration - ruckig.duration) < 0.05
    assert_within_limits(traj, limits)
