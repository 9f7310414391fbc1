"""Planning: IK round trips, Ruckig limits, straight Cartesian lines, the collision model."""
import numpy as np
import pytest

from app.failures import NoIKSolution, NoPath, PathCollides
from app.motion.cartesian import MAX_JOINT_JUMP, line_path
from app.motion.ik import IKConfig, reach_failure, solve
from app.motion.scene import PlanningScene
from app.motion.trajectory import path_timing, remainder, through_waypoints
from app.simcell.cell import CellConfig
from hardware.gripper_geometry import GripperGeometry
from hardware.interfaces import JointLimits
from hardware.kinematics import UR5Kinematics
from hardware.robot_description import HOME_Q
from hardware.se3 import line_length, make_pose, rotation_angle, rotvec_to_matrix
from hardware.sim.arm import JOINT_ACCELERATION_LIMIT, JOINT_JERK_LIMIT


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
    config = IKConfig()
    for _ in range(100):
        q_true = rng.uniform(-np.pi, np.pi, 6)
        target = kin.fk(q_true)
        q = solve(kin, target, HOME_Q, None, config)
        reached = kin.fk(q)
        assert np.linalg.norm(reached[:3, 3] - target[:3, 3]) < 1e-4
        assert np.degrees(rotation_angle(reached[:3, :3].T @ target[:3, :3])) < 0.01


def test_closed_form_ik_gives_every_branch_and_its_frames_are_the_urdf_s(kin):
    """ur_analytic_ik's tool0 FK is this URDF's; ik_all recovers the configuration a pose came from
    among up to 8 distinct branches, each reaching the pose, and the 8 of a generic pose differ."""
    import ur_analytic_ik

    rng = np.random.default_rng(3)
    counts = []
    for _ in range(100):
        q_true = rng.uniform(-np.pi, np.pi, 6)
        assert np.allclose(ur_analytic_ik.ur5.forward_kinematics(*q_true), kin.frame_pose(q_true, "tool0"), atol=1e-9)
        target = kin.fk(q_true)
        branches = kin.ik_all(target, q_true)
        assert any(np.abs(q - q_true).max() < 1e-6 for q in branches)
        for q in branches:
            assert np.abs(kin.fk(q) - target).max() < 1e-6
        assert all(np.abs(a - b).max() > 1e-3 for i, a in enumerate(branches) for b in branches[:i])
        counts.append(len(branches))
    assert max(counts) == 8 and min(counts) >= 2
    rounded = kin.fk(q_true).astype(np.float32).astype(float)  # a pose from a float32 network: not quite a rotation
    assert kin.ik_all(rounded, q_true), "a pose 1e-7 off a rotation still has its branches"


def test_ik_out_of_reach_and_colliding_poses_are_refused_with_reasons(kin, scene):
    far = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [1.5, 0.0, 0.2])
    with pytest.raises(NoIKSolution, match="out of reach"):
        solve(kin, far, HOME_Q, scene, IKConfig())
    below_table = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.5, 0.0, -0.05])
    with pytest.raises(NoIKSolution, match="collides .*table"):
        solve(kin, below_table, HOME_Q, scene, IKConfig())


def test_scene_flags_the_table_and_not_home(scene):
    assert scene.collisions(HOME_Q) == []
    down = HOME_Q.copy()
    down[1] = 0.3  # upper arm pointing into the table
    assert any(hit.endswith("-table") for hit in scene.collisions(down))


def test_the_planners_quick_check_agrees_with_the_full_contact_list(kin, scene):
    rng = np.random.default_rng(3)
    scene.add_cloud("box", rng.uniform([0.35, -0.2, 0.0], [0.55, 0.0, 0.12], (400, 3)))
    try:
        qs = [HOME_Q + rng.uniform(-1.5, 1.5, 6) for _ in range(300)]
        hits = [scene.collisions(q) for q in qs]
        assert 50 < sum(map(bool, hits)) < 250  # both kinds of state are in the sample
        assert any(any(h.endswith("-box") for h in hs) for hs in hits)
        assert [scene.is_free(q) for q in qs] == [not hs for hs in hits]
        assert [scene.is_free(q, ("box",)) for q in qs] == [not [h for h in hs if not h.endswith("-box")] for hs in hits]
    finally:
        scene.remove("box")


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


def test_a_straight_timed_transit_follows_the_joint_segments_the_planner_checked(limits):
    """Timed straight, between two waypoints every joint runs the same profile scaled (phase
    synchronisation, a UR's moveJ): each sample lies on the segment the sampling planner checked."""
    rng = np.random.default_rng(2)
    waypoints = [HOME_Q + rng.uniform(-1.0, 1.0, 6) * [1.0, 0.3, 0.5, 1.0, 0.2, 2.0] for _ in range(3)]
    traj = through_waypoints(waypoints, limits, straight=True)
    middle = int(np.argmin(np.abs(traj.q - waypoints[1]).max(axis=1)))  # where the chain rests at the waypoint
    for (a, b), q in zip(zip(waypoints[:-1], waypoints[1:]), (traj.q[: middle + 1], traj.q[middle:])):
        s = (q - a) @ (b - a) / ((b - a) @ (b - a))  # (T,) how far along the segment
        assert len(q) > 20 and np.abs(a + s[:, None] * (b - a) - q).max() < 1e-6


def test_the_rest_of_a_trajectory_runs_on_from_where_the_arm_stopped_to_its_end(limits):
    """`remainder`: from a stop part way (at rest, a little off the path), along the rest of the path
    to its end, at rest at both ends and within the joint limits; for a path well under way, nothing
    of what was already done."""
    rng = np.random.default_rng(3)
    waypoints = [HOME_Q + rng.uniform(-1.0, 1.0, 6) * [1.0, 0.3, 0.5, 1.0, 0.2, 2.0] for _ in range(3)]
    traj = through_waypoints(waypoints, limits, straight=True)
    stop = traj.q[len(traj.q) // 3] + 1e-3
    rest = remainder(traj, stop, limits)
    np.testing.assert_allclose(rest.q[0], stop, atol=1e-9)
    np.testing.assert_allclose(rest.end, traj.end, atol=1e-9)
    assert np.abs(rest.qd[[0, -1]]).max() < 1e-9 and (np.abs(rest.qd) <= limits.velocity + 1e-6).all()
    done = traj.q[: len(traj.q) // 3 - 5]  # (K, 6) already run
    nearest_done = np.abs(rest.q[:, None, :] - done[None]).max(axis=2).min(axis=1)  # (T,)
    assert nearest_done[5:].min() > 1e-3  # it does not go back over them


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


class _SteepWrist:
    """A stand-in kinematics: joint 4 follows the TCP's x, steeply (0.12 rad per 4 mm step), plus a
    jump of pi past x = `flip_at` (a branch switch) if given; fk is not needed by line_path."""

    def __init__(self, flip_at: float | None = None) -> None:
        self.flip_at = flip_at

    def ik_nearest(self, T, q_ref):
        q = np.zeros(6)
        q[3] = 30.0 * T[0, 3] + (np.pi if self.flip_at is not None and T[0, 3] > self.flip_at else 0.0)
        return q


def test_a_fast_but_continuous_line_is_kept_and_a_branch_switch_refused():
    T0, T1 = make_pose(t=[0.0, 0.0, 0.3]), make_pose(t=[0.1, 0.0, 0.3])
    path = line_path(_SteepWrist(), T0, T1, np.zeros(6))  # every step moves 0.12 rad > MAX_JOINT_JUMP
    assert np.abs(np.diff(path, axis=0)).max() > MAX_JOINT_JUMP
    assert np.allclose(path[:, 3], 30.0 * np.linspace(0.0, 0.1, len(path)))
    with pytest.raises(NoIKSolution, match="flip its configuration at 5[0-9]%"):
        line_path(_SteepWrist(flip_at=0.05), T0, T1, np.zeros(6))


def test_retreat_near_the_wrist_singularity_stays_on_its_line(kin):
    q_hang = np.array([3.293, -1.2, 2.106, -3.054, -0.109, -0.201])  # a teacher's hang on the rack, q5 ~ 0
    T0 = kin.fk(q_hang)
    T1 = T0 @ make_pose(t=[0.0, 0.0, -0.10])  # the retreat: back along the tool axis
    path = line_path(kin, T0, T1, q_hang)
    assert np.abs(np.diff(path, axis=0)).max() > MAX_JOINT_JUMP  # this line needs the closer look
    u = T1[:3, 3] - T0[:3, 3]
    for a, b in zip(path[:-1], path[1:]):
        for w in np.linspace(0.0, 1.0, 5):  # between the points too: the trajectory interpolates q
            p = kin.fk((1 - w) * a + w * b)[:3, 3] - T0[:3, 3]
            assert np.linalg.norm(p - (p @ u) / (u @ u) * u) < 0.002


def test_a_held_object_is_carried_and_collides_where_it_goes(kin, scene):
    rng = np.random.default_rng(0)
    cube = rng.uniform([0.45, -0.05, 0.03], [0.53, 0.03, 0.09], (400, 3))  # 8 cm of points, 3 cm above the table
    T_grasp = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.49, -0.01, 0.10])
    q_grasp = solve(kin, T_grasp, HOME_Q, None)
    T_rack = CellConfig().fixture_pose("rack")
    T_at_post = make_pose(T_grasp[:3, :3], T_rack[:3, 3] + [0.0, 0.0, 0.15])  # the cube's centre at the post
    q_post = solve(kin, T_at_post @ make_pose(t=[0.0, 0.0, -0.01]), HOME_Q, None)
    scene.add_cloud("object", cube)
    try:
        with scene.holding("object", T_grasp):
            assert not [h for h in scene.collisions(q_grasp, ("object",)) if h.startswith("held")]  # the gripper holds it
            assert "held-rack" in scene.collisions(q_post, ("object",))
        assert not [h for h in scene.collisions(q_post, ("object",)) if h.startswith("held")]  # let go: not carried
    finally:
        scene.remove("object")
    with scene.holding("nothing", T_grasp):  # not a cloud obstacle: nothing is carried
        assert scene.held is None


def test_reach_failure_passes_a_pose_over_the_table_and_refuses_table_rack_and_far_poses(kin, scene):
    down = rotvec_to_matrix([np.pi, 0, 0])  # tool pointing down
    failure = reach_failure(kin, scene, HOME_Q)

    def reachable(T):
        return failure(T) is None

    assert reachable(make_pose(down, [0.5, 0.0, 0.15]))
    assert scene.gripper_collisions(make_pose(down, [0.5, 0.0, 0.01])) == ["table"]  # fingertips 1 cm into the table
    assert not reachable(make_pose(down, [0.5, 0.0, 0.01]))
    rack = CellConfig().fixture_pose("rack")
    assert not reachable(make_pose(down, rack[:3, 3] + [0.0, 0.0, 0.2]))  # the open gripper around the post
    assert not reachable(make_pose(down, [1.5, 0.0, 0.2]))  # beyond the UR5's reach


def _pillar_between_two_reaches(kin):
    """Two top-down reaches 44 cm apart (y = -0.22, 0.22) and a 6 cm pillar, 25 cm tall, between them."""
    down = kin.fk(HOME_Q)[:3, :3]
    q0, q1 = (kin.ik(make_pose(down, [0.45, y, 0.15]), HOME_Q) for y in (-0.22, 0.22))
    grid = np.stack(np.meshgrid(np.linspace(-0.03, 0.03, 4), np.linspace(-0.03, 0.03, 4), np.linspace(0, 0.25, 10)), -1)
    return q0, q1, grid.reshape(-1, 3) + [0.45, 0.0, 0.0]  # (160, 3)


def test_sampling_planner_goes_around_an_obstacle_on_the_direct_path(kin, scene):
    from app.motion.sampling import SamplingConfig, densify, plan_joint_path

    q0, q1, pillar = _pillar_between_two_reaches(kin)
    scene.add_cloud("pillar", pillar)
    try:
        assert scene.collisions(q0) == [] and scene.collisions(q1) == []
        assert any(scene.collisions(q) for q in densify(np.array([q0, q1]), 0.01))  # the straight path hits it
        path = plan_joint_path(scene, q0, q1)
        assert np.array_equal(path[0], q0) and np.array_equal(path[-1], q1)
        assert not any(scene.collisions(q) for q in densify(path, 0.005))  # every state, at the scene's margin
        assert np.array_equal(plan_joint_path(scene, q0, q1), path)  # seeded: the same problem, the same path
        assert not np.array_equal(plan_joint_path(scene, q0, q1, config=SamplingConfig(seed=2)), path)
    finally:
        scene.remove("pillar")


def test_the_search_budget_is_states_checked_not_seconds(kin, scene, monkeypatch):
    """A slower collision check (a busy machine) plans the same path; a search that cannot succeed
    stops after its states, long before its time cap."""
    import time

    from app.motion.sampling import SamplingConfig, plan_joint_path

    q0, q1, pillar = _pillar_between_two_reaches(kin)
    scene.add_cloud("pillar", pillar)
    try:
        path = plan_joint_path(scene, q0, q1)
        is_free = scene.is_free
        monkeypatch.setattr(scene, "is_free", lambda q, ignore=(): time.sleep(2e-4) or is_free(q, ignore))
        assert np.array_equal(plan_joint_path(scene, q0, q1), path)
        checked = []
        ends_only = lambda q: checked.append(q) or bool(np.allclose(q, q0) or np.allclose(q, q1))  # noqa: E731
        start = time.perf_counter()
        with pytest.raises(NoPath, match="within 300 states"):
            plan_joint_path(scene, q0, q1, config=SamplingConfig(states=300, timeout=100.0), allowed=ends_only)
        assert len(checked) >= 300 and time.perf_counter() - start < 5.0
    finally:
        scene.remove("pillar")


def test_sampling_planner_refuses_a_colliding_goal_at_once_and_names_the_contact(kin, scene):
    import time

    from app.motion.sampling import plan_joint_path

    q0, q1, pillar = _pillar_between_two_reaches(kin)
    scene.add_cloud("pillar", pillar)
    try:
        inside = q1.copy()
        for q in np.linspace(q0, q1, 50):  # a state on the straight path that is in the pillar
            if scene.collisions(q):
                inside = q
                break
        assert scene.collisions(inside)
        start = time.perf_counter()
        with pytest.raises(NoPath, match="goal collides .*pillar"):
            plan_joint_path(scene, q0, inside)  # RRT-Connect alone would sample for its 2 s
        assert time.perf_counter() - start < 0.5
        with pytest.raises(NoPath, match="start collides .*pillar"):
            plan_joint_path(scene, inside, q1)
    finally:
        scene.remove("pillar")


def test_transit_around_an_obstacle_is_collision_free_once_timed(kin, limits, scene):
    from app.motion.planner import Planner

    q0, q1, pillar = _pillar_between_two_reaches(kin)
    scene.add_cloud("pillar", pillar)
    try:
        traj = Planner(kin, limits, scene).transit(q0, q1, "around")
        assert np.allclose(traj.q[0], q0) and np.allclose(traj.q[-1], q1, atol=1e-6)
        assert not any(scene.collisions(q) for q in traj.q)  # every 4 ms sample, not just the checked ones
        assert np.all(np.abs(traj.qd) <= limits.velocity + 1e-6)
    finally:
        scene.remove("pillar")


def test_upper_arm_below_horizontal_hits_the_table_not_its_own_base(scene):
    down = HOME_Q.copy()
    down[1] = 0.6  # upper arm 34 degrees below horizontal: its meshes overlap the base's by 5 mm here
    hits = scene.collisions(down)
    assert "upper_arm_link-table" in hits and "base_link-upper_arm_link" not in hits
    assert all(pair in scene.self_pairs for pair in [("base_link", "forearm_link"), ("shoulder_link", "forearm_link")])


def test_a_carried_object_is_planned_around_what_the_empty_gripper_clears(kin, limits, scene):
    """A 15 cm post under a transit at 27 cm: the gripper passes over it, a 12 cm box held below the
    TCP would sweep through it - the planner refuses that path and finds one that clears it."""
    from app.motion.planner import Planner
    from app.motion.sampling import densify

    down = kin.fk(HOME_Q)[:3, :3]
    q0, q1 = (kin.ik(make_pose(down, [0.45, y, 0.27]), HOME_Q) for y in (-0.22, 0.22))
    T_grasp = make_pose(down, [0.30, -0.30, 0.17])
    box = np.random.default_rng(0).uniform([0.26, -0.34, 0.02], [0.34, -0.26, 0.14], (300, 3))  # under the TCP
    post = np.stack(np.meshgrid(np.linspace(-0.03, 0.03, 4), np.linspace(-0.03, 0.03, 4), np.linspace(0, 0.15, 8)), -1)
    scene.add_cloud("post", post.reshape(-1, 3) + [0.45, 0.0, 0.0])
    scene.add_cloud("object", box)
    hits = lambda path: {h for q in densify(path, 0.005) for h in scene.collisions(q, ("object",))}  # noqa: E731
    try:
        assert hits(np.array([q0, q1])) == set()  # empty-handed, the direct path is free
        with scene.holding("object", T_grasp):
            assert hits(np.array([q0, q1])) == {"held-post"}
            traj = Planner(kin, limits, scene).transit(q0, q1, "carry", ignore=("object",))
            assert not any(scene.collisions(q, ("object",)) for q in traj.q)
    finally:
        scene.remove("post")
        scene.remove("object")


def test_fingers_closed_on_a_held_object_clear_what_the_open_ones_hit(kin, scene):
    """A 1 cm post 4.8 cm beside the TCP, along the closing axis: inside the open finger (inner face
    at 4.25 cm, outer at 5.45 cm), 2.6 cm clear of one closed to 2 cm - for the gripper alone and on the arm."""
    down = rotvec_to_matrix([np.pi, 0, 0])
    T = make_pose(down, [0.5, 0.0, 0.15])
    post = T[:3, 3] + 0.048 * T[:3, 1] + np.stack(np.meshgrid(*[np.linspace(-0.005, 0.005, 3)] * 3), -1).reshape(-1, 3)
    scene.add_cloud("post", post)
    try:
        q = kin.ik(T, HOME_Q)
        assert scene.gripper_collisions(T) == ["post"]
        assert any(hit.startswith("finger_") and hit.endswith("-post") for hit in scene.collisions(q))
        with scene.fingers(0.02):
            assert scene.gripper_collisions(T) == [] and not any(hit.endswith("-post") for hit in scene.collisions(q))
        assert scene.gripper_collisions(T) == ["post"]  # open again after the block
    finally:
        scene.remove("post")


def test_gripper_clear_refuses_a_grasp_from_under_the_table_and_passes_the_same_from_above(scene):
    """A side wall seen as a cloud; grasped from above it is clear, the same contact from below puts
    the gripper into the table (the back-off cannot help: the approach points up)."""
    from app.jobs.clearance import gripper_clear

    wall = np.array([[0.5, y, z] for y in np.linspace(-0.01, 0.01, 5) for z in np.linspace(0.0, 0.1, 40)])
    clear = gripper_clear(scene, wall)
    down = rotvec_to_matrix([np.pi, 0, 0])  # approach -z
    assert clear(make_pose(down, [0.5, 0.0, 0.09]))
    assert not clear(make_pose(np.eye(3), [0.5, 0.0, 0.02]))  # approach +z: from under the table


def test_approach_clear_passes_fingers_beside_a_wall_and_refuses_one_coming_down_on_it():
    """A thin wall (a rim, 2 mm) along x at y = 0; fingers straddling it close across it (TCP y = 0),
    a TCP moved 4.25 cm sideways puts one finger's path onto the wall's top edge."""
    from app.jobs.clearance import approach_clear
    from hardware.gripper_geometry import GripperGeometry

    g = GripperGeometry()
    wall = np.array([[x, y, z] for x in np.linspace(0.48, 0.52, 9) for y in (-0.001, 0.001)
                     for z in np.linspace(0.0, 0.08, 17)])
    down = rotvec_to_matrix([np.pi, 0, 0])  # tool z down; its y axis is the base's -y: fingers at +-y
    straddle = make_pose(down, [0.5, 0.0, 0.07])
    assert approach_clear(straddle, wall, 0.10, g)
    onto = make_pose(down, [0.5, g.stroke / 2 + g.finger[1] / 2, 0.07])
    assert not approach_clear(onto, wall, 0.10, g)
    above = make_pose(down, [0.5, g.stroke / 2 + g.finger[1] / 2, 0.20])  # the fingertips stop above the wall
    assert approach_clear(above, wall, 0.10, g)


def test_the_planning_scene_does_not_grow_with_each_jobs_cloud():
    """PyBullet keeps every vertex list and mesh shape it is given; the scene hands it hull vertices
    and one carried shape per cloud, so 40 jobs' clouds (added, carried three times, removed) cost
    little (a 2,048-point list was 0.6 MB a call, 40 x 4 calls about 100 MB)."""
    from app.bench.memory import resident_mb

    scene = PlanningScene(CellConfig())
    rng = np.random.default_rng(0)
    try:
        def job() -> None:
            cloud = rng.normal(size=(1024, 3)) * 0.03 + [0.5, 0.0, 0.06]
            scene.add_cloud("object", cloud, eye=np.array([1.25, 0.0, 0.55]))
            for _ in range(3):
                with scene.holding("object", make_pose(t=[0.5, 0.0, 0.1])):
                    scene.collisions(np.array(CellConfig().arm.home_q))
            scene.remove("object")

        for _ in range(5):
            job()
        before = resident_mb()
        for _ in range(40):
            job()
        assert resident_mb() - before < 15.0
    finally:
        scene.close()


def test_a_blocked_approach_line_is_replaced_by_a_shorter_one_that_keeps_the_grasp(kin, limits, scene):
    """A stand-in obstacle fills the last 4 cm of the default 10 cm approach line (TCP 7-11 cm back
    along a tilted grasp's axis): the plan keeps the grasp pose and approaches from 6 cm; without the
    alternatives it fails at the approach."""
    from dataclasses import replace

    from app.motion.config import MotionConfig
    from app.motion.planner import Planner

    tilted = rotvec_to_matrix([0.0, np.pi / 4, 0.0]) @ rotvec_to_matrix([np.pi, 0, 0])  # the lift is not the approach
    T_grasp = make_pose(tilted, [0.5, 0.05, 0.15])
    T_place = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.45, -0.15, 0.15])
    real = scene.collisions

    def collisions(q, ignore=()):
        p = (np.linalg.inv(T_grasp) @ kin.fk(q))[:3, 3]  # the TCP in the grasp's frame
        blocked = np.linalg.norm(p[:2]) < 0.015 and -0.11 < p[2] < -0.07
        return real(q, ignore) + (["gripper_palm-box"] if blocked else [])

    scene.collisions = collisions
    plan = Planner(kin, limits, scene).pick_place(HOME_Q, T_grasp, T_place, np.array([0.0, 0.0, 1.0]))
    approach = plan.segment("approach")
    start = np.linalg.inv(plan.T_base_grasp) @ kin.fk(approach.q[0])
    assert np.allclose(start[:3, 3], [0.0, 0.0, -0.06], atol=1e-4)
    assert np.allclose(kin.fk(approach.end), plan.T_base_grasp, atol=1e-4)
    assert not any("box" in h for q in approach.q for h in collisions(q))
    only_default = replace(MotionConfig(), shorter=(), approach_cone=0.0)
    with pytest.raises(PathCollides, match="approach: collision .*gripper_palm-box"):
        Planner(kin, limits, scene, only_default).pick_place(HOME_Q, T_grasp, T_place, np.array([0.0, 0.0, 1.0]))


def test_a_blocked_lift_is_replaced_by_one_tilted_off_vertical(kin, limits, scene):
    """A stand-in obstacle fills the vertical line 4-14 cm above the grasp (within 8 mm of it): the full
    and the shorter lifts (12, 7.2, 4.8 cm) enter it, one 15 degrees off vertical passes beside it."""
    from app.motion.planner import Planner

    T_grasp = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.5, 0.05, 0.15])
    T_place = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.45, -0.15, 0.15])
    real = scene.collisions

    def collisions(q, ignore=()):
        p = kin.fk(q)[:3, 3] - T_grasp[:3, 3]
        blocked = np.linalg.norm(p[:2]) < 0.008 and 0.04 < p[2] < 0.14
        return real(q, ignore) + (["gripper_palm-box"] if blocked else [])

    scene.collisions = collisions
    plan = Planner(kin, limits, scene).pick_place(HOME_Q, T_grasp, T_place, np.array([0.0, 0.0, 1.0]))
    lift = kin.fk(plan.segment("lift").end)[:3, 3] - plan.T_base_grasp[:3, 3]
    assert np.degrees(np.arccos(lift[2] / np.linalg.norm(lift))) == pytest.approx(15.0, abs=1e-3)
    assert np.linalg.norm(lift) == pytest.approx(0.12, abs=1e-4)
    assert not any("box" in h for q in plan.segment("lift").q for h in collisions(q))


def test_line_alternatives_are_the_axis_shorter_and_a_cone_of_six_about_it():
    from app.motion.config import MotionConfig
    from app.motion.line_offsets import line_offsets

    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    offsets = np.array(line_offsets(axis, 0.1, MotionConfig()))  # (9, 3)
    np.testing.assert_allclose(offsets[:3], np.outer([1.0, 0.6, 0.4], 0.1 * axis), atol=1e-12)
    cone = offsets[3:] / 0.1
    np.testing.assert_allclose(np.linalg.norm(cone, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.degrees(np.arccos(cone @ axis)), 15.0, atol=1e-9)
    across = cone - np.outer(cone @ axis, axis)
    turns = np.degrees(np.arccos(np.clip(np.sum(across * np.roll(across, -1, axis=0), axis=1)
                                         / np.linalg.norm(across, axis=1) ** 2, -1, 1)))
    np.testing.assert_allclose(turns, 60.0, atol=1e-9)  # six azimuths, evenly spaced


def test_a_pick_alone_ends_at_the_lift_and_its_place_planned_from_there_ends_at_the_place(kin, limits, scene):
    """pick_place with no place plans to the pre-grasp, the approach and the lift only; place_from at the
    lift's end (as after the second look) then carries the held grasp to the place and goes home."""
    from app.motion.planner import Planner

    T_grasp = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.5, 0.05, 0.15])
    T_place = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.45, -0.15, 0.15])
    planner = Planner(kin, limits, scene)
    pick = planner.pick_place(HOME_Q, T_grasp, None, None)
    assert [s.label for s in pick.segments] == ["to pre-grasp", "approach", "lift"] and pick.T_base_place is None
    assert np.allclose(kin.fk(pick.segment("approach").end), pick.T_base_grasp, atol=1e-4)
    rest = planner.place_from(pick.segment("lift").end, pick.T_base_grasp, T_place, np.array([0.0, 0.0, 1.0]))
    assert [s.label for s in rest.segments] == ["carry", "place", "retreat", "clear", "home"]
    assert np.allclose(rest.segment("carry").q[0], pick.segment("lift").end)
    assert np.allclose(kin.fk(rest.segment("place").end), T_place, atol=1e-4)


class _DriverArm:
    """Stands at q; runs a trajectory only if it starts within 0.01 rad of it (the drivers' check)."""

    def __init__(self, q):
        self.q, self.ran = np.asarray(q, float), None

    def getActualQ(self):
        return self.q.copy()

    def getLastError(self):
        return ""

    def executeTrajectory(self, times, q, qd=None):
        if np.abs(q[0] - self.q).max() > 0.01:
            raise ValueError("trajectory does not start at the arm's current joint positions")
        self.ran, self.q = np.asarray(q).copy(), np.asarray(q[-1], float).copy()
        return True


def test_a_segment_starts_where_a_sagging_arm_stands_and_a_far_one_is_still_refused():
    """An arm left 0.012 rad off the next segment's start (within the 0.02 rad end tolerance) runs it from
    where it stands; 0.03 rad off, the driver's refusal stands."""
    from app.motion.executor import execute
    from app.motion.trajectory import JointTrajectory

    path = np.linspace(np.zeros(6), np.full(6, 0.5), 50)
    traj = JointTrajectory(np.linspace(0.0, 1.0, 50), path, np.gradient(path, axis=0), "retreat")
    sagged = np.array([0.0, 0.012, 0.0, 0.0, 0.0, 0.0])
    arm = _DriverArm(sagged)
    execute(arm, traj, 0.02)
    assert np.allclose(arm.ran[0], sagged) and np.allclose(arm.ran[1:], path[1:]) and np.allclose(arm.q, path[-1])
    with pytest.raises(ValueError, match="does not start"):
        execute(_DriverArm(sagged * 2.5), traj, 0.02)


def test_an_arm_pushed_off_a_trajectorys_start_is_brought_back_and_one_close_by_is_left_alone():
    from app.motion.executor import back_to_start
    from app.motion.trajectory import JointTrajectory
    from hardware.sim.arm import SimArm, SimArmConfig
    from hardware.sim.robot import SimRobot
    from hardware.sim.world import SimWorld

    world = SimWorld()
    arm = SimArm(SimArmConfig(), SimRobot(world))
    with world, arm:
        start = np.array(HOME_Q)
        traj = JointTrajectory(np.array([0.0, 1.0]), np.array([start, start + 0.1]), np.zeros((2, 6)), "retreat")
        pushed = start + [0.0, 0.0, 0.0, 0.07, 0.0, 0.0]  # the wrist, as a gripper letting go pushed it
        assert arm.moveJ(pushed)
        back_to_start(arm, traj, tolerance=0.02)
        assert np.abs(arm.getActualQ() - start).max() < 2e-3
        near = start + [0.0, 0.0, 0.0, 0.015, 0.0, 0.0]
        assert arm.moveJ(near)
        back_to_start(arm, traj, tolerance=0.02)  # within the tolerance `execute` starts from where it stands
        assert np.abs(arm.getActualQ() - near).max() < 2e-3


def test_a_sampled_path_whose_default_timing_leaves_its_segments_is_timed_straight(kin, limits, scene, monkeypatch):
    """A planner whose every state off the sampled segments is 'in collision' (what a narrow passage
    is): the direct move and the default timing of the sampled path fail, the straight timing of the
    same waypoints is taken."""
    import app.motion.planner as ex

    q0 = np.array(HOME_Q)
    via = q0 + [0.8, -0.3, 0.5, 0.9, 0.2, 1.5]
    q1 = q0 + [1.2, 0.1, 0.2, 1.4, -0.3, 0.6]
    waypoints = np.array([q0, via, q1])

    def off_the_segments(traj, ignore, allowed=None):
        middle = int(np.argmin(np.abs(traj.q - via).max(axis=1)))
        if np.abs(traj.q[middle] - via).max() > 1e-9:
            return ["direct-off"]
        for (a, b), q in zip(((q0, via), (via, q1)), (traj.q[: middle + 1], traj.q[middle:])):
            s = (q - a) @ (b - a) / ((b - a) @ (b - a))
            if np.abs(a + s[:, None] * (b - a) - q).max() > 1e-6:
                return ["curved-off"]
        return []

    monkeypatch.setattr(ex, "plan_joint_path", lambda *args, **kw: waypoints)
    planner = ex.Planner(kin, limits, scene)
    monkeypatch.setattr(planner, "_collisions", off_the_segments)
    traj = planner.transit(q0, q1, "carry")
    assert off_the_segments(traj, ()) == [] and np.allclose(traj.end, q1)


def _side_grasp(kin):
    """A side grasp as of a bottle at its neck: the approach (tool z) horizontal, the tool's x up, the
    fingers' axis (tool y) horizontal across the approach; and its IK solution near home."""
    R = np.column_stack([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # tool x, y, z in the base frame
    T = make_pose(R, [0.45, 0.10, 0.30])
    return T, kin.ik(T, HOME_Q)


def test_the_carry_constraint_bounds_the_turn_about_the_fingers_axis_and_no_other(kin):
    from app.motion.carry_pivot import held_without_pivot

    T0, q0 = _side_grasp(kin)
    turned = lambda rotvec: kin.ik(T0 @ make_pose(rotvec_to_matrix(rotvec)), q0)  # noqa: E731
    allowed = held_without_pivot(kin, q0, q0, 45.0)
    for degrees, ok in ((20.0, True), (44.0, True), (-44.0, True), (46.0, False), (90.0, False), (180.0, False)):
        assert allowed(turned([0.0, np.radians(degrees), 0.0])) is ok, degrees  # about the fingers' axis
    for degrees in (30.0, 90.0, 180.0):  # about the tool's x, the bottle's own axis: any turn
        assert allowed(turned([np.radians(degrees), 0.0, 0.0]))
    for degrees, ok in ((30.0, True), (85.0, True), (180.0, False)):  # about the approach: until it stands on its head
        assert allowed(turned([0.0, 0.0, np.radians(degrees)])) is ok, degrees
    q_end = turned([0.0, np.radians(70.0), 0.0])  # an end that needs more is allowed that much
    wider = held_without_pivot(kin, q0, q_end, 45.0)
    assert wider(q_end) and wider(turned([0.0, np.radians(65.0), 0.0])) and not wider(turned([0.0, np.radians(80.0), 0.0]))


def test_the_sampling_planner_keeps_a_path_constraint_on_every_state(kin, limits, scene):
    """Two reaches whose direct joint path passes the elbow over 1.2 rad; the constraint forbids that
    on the middle third of the base's turn: the planner finds a way with the elbow bent less, and the
    timed transit keeps it at every sample."""
    from app.motion.planner import Planner
    from app.motion.sampling import densify, plan_joint_path

    q0, q1, _ = _pillar_between_two_reaches(kin)
    lo, hi = np.sort([q0[0], q1[0]])
    third = (hi - lo) / 3
    elbow = 0.5 * (abs(q0[2]) + min(abs(q0[2]), abs(q1[2])))
    allowed = lambda q: not (lo + third < q[0] < hi - third and abs(q[2]) > elbow - 0.3)  # noqa: E731
    assert allowed(q0) and allowed(q1) and not all(allowed(q) for q in densify(np.array([q0, q1]), 0.01))
    path = plan_joint_path(scene, q0, q1, allowed=allowed)
    assert all(allowed(q) for q in densify(path, 0.005))
    traj = Planner(kin, limits, scene).transit(q0, q1, "constrained", allowed=allowed)
    assert all(allowed(q) for q in traj.q) and np.allclose(traj.q[-1], q1, atol=1e-6)


def test_a_carry_that_cannot_keep_the_object_from_pivoting_is_planned_without_the_constraint(kin, limits, scene,
                                                                                            monkeypatch):
    import app.motion.planner as planner_module
    from app.motion.config import MotionConfig
    from app.motion.sampling import SamplingConfig

    T0, q0 = _side_grasp(kin)
    q1 = kin.ik(make_pose(t=[0.0, -0.15, 0.0]) @ T0, q0)
    assert not scene.collisions(q0) and not scene.collisions(q1)
    planner = planner_module.Planner(kin, limits, scene, MotionConfig(
        sampling=SamplingConfig(states=2_000)))
    lever = 0.1  # m: a bottle held at its neck
    traj, kept = planner.carry(q0, q1, lever=lever)
    assert kept and np.allclose(traj.q[-1], q1, atol=1e-6)
    ends_only = lambda kin_, a, b, extra: (lambda q: bool(np.allclose(q, a) or np.allclose(q, b)))  # noqa: E731
    monkeypatch.setattr(planner_module, "held_without_pivot", ends_only)  # nothing between the ends is allowed
    with pytest.raises(NoPath, match="constrained"):
        planner.transit(q0, q1, "carry", allowed=ends_only(kin, q0, q1, 0.0))
    traj, kept = planner.carry(q0, q1, lever=lever)  # the constraint cannot be kept: planned as any transit
    assert not kept and np.allclose(traj.q[0], q0) and np.allclose(traj.q[-1], q1, atol=1e-6)
    assert planner.carry(q0, q1, lever=0.04)[1]  # a mug held at its rim: no constraint to keep


def test_the_held_lever_is_the_centroids_distance_from_the_fingers_axis(kin, limits, scene):
    from app.motion.planner import OBJECT, Planner

    T_grasp, _ = _side_grasp(kin)  # the tool's x up, y (the fingers' axis) along the base's y
    planner = Planner(kin, limits, scene)
    assert planner.held_lever(T_grasp) == 0.0  # no cloud of the object: nothing to pivot
    blob = np.random.default_rng(0).normal(0.0, 0.005, (200, 3))
    blob -= blob.mean(axis=0)
    scene.add_cloud(OBJECT, blob + T_grasp[:3, 3] + [0.0, 0.05, -0.11])  # 11 cm below the TCP, 5 cm along y
    try:
        assert planner.held_lever(T_grasp) == pytest.approx(0.11, abs=1e-6)  # along the axis does not count
    finally:
        scene.remove(OBJECT)


@pytest.mark.parametrize("pivots_on", [(True, False), (True, True)])
def test_a_carry_that_may_pivot_the_object_sends_the_planner_to_the_other_half_turn(kin, limits, scene, monkeypatch,
                                                                                   pivots_on):
    """The first half-turn's carry cannot keep the object from pivoting: the other half-turn is planned
    and taken when its carry can; when neither can, the first is kept, with the note."""
    from app.motion.planner import CARRY_MAY_PIVOT, HALF_TURN, Planner

    T_grasp = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.5, 0.05, 0.15])
    T_place = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.45, -0.15, 0.15])
    planner = Planner(kin, limits, scene)
    flips = planner._flips_shortest_first(HOME_Q, T_grasp)
    carries = iter(pivots_on)
    carry = Planner.carry
    monkeypatch.setattr(Planner, "carry", lambda self, *a, **k: (carry(self, *a, **k)[0], not next(carries)))
    plan = planner.pick_place(HOME_Q, T_grasp, T_place, np.array([0.0, 0.0, 1.0]))
    taken = flips[1] if pivots_on == (True, False) else flips[0]
    assert np.allclose(plan.T_base_grasp, T_grasp @ taken) and np.allclose(plan.T_base_place, T_place @ taken)
    assert (CARRY_MAY_PIVOT in plan.notes) == all(pivots_on)
    assert any(np.allclose(f, HALF_TURN) for f in flips)


def test_an_object_held_near_its_centroid_gets_a_short_search_for_a_carry_that_keeps_it(kin, limits, scene,
                                                                                       monkeypatch):
    """A carry whose direct path stands the object on its head (the wrist's last joint a full turn):
    the constrained search runs for `short_lever_search` for a mug held at its rim, for the planner's
    full time for a bottle held at its neck, and only the latter's fallback is noted."""
    import app.motion.planner as planner_module
    from app.motion.config import MotionConfig
    from app.motion.sampling import SamplingConfig

    T0, q0 = _side_grasp(kin)
    q1 = q0.copy()
    q1[5] -= 2 * np.pi  # the same pose, the tool turned once about its axis on the way
    budgets = []
    real = planner_module.plan_joint_path

    def spy(scene_, a, b, ignore=(), config=SamplingConfig(), allowed=None):
        budgets.append((config.states, allowed is not None))
        return real(scene_, a, b, ignore, config, allowed)

    monkeypatch.setattr(planner_module, "plan_joint_path", spy)
    config = MotionConfig(sampling=SamplingConfig(states=5_000))
    planner = planner_module.Planner(kin, limits, scene, config)
    for lever, budget, noted in ((0.04, config.short_lever_search, False), (0.11, 5_000, True)):
        budgets.clear()
        traj, kept = planner.carry(q0, q1, lever=lever)
        assert budgets[0] == (budget, True) and kept is not noted
        assert np.allclose(traj.q[-1], q1, atol=1e-6)


def test_a_transit_is_collision_checked_as_densely_at_any_speed():
    """checked_indices keeps a sample wherever a joint has moved more than the step since the last kept
    one: a path sampled four times as finely gives the same checked states."""
    from app.motion.planner import checked_indices

    coarse = np.zeros((41, 6))
    coarse[:, 0] = np.linspace(0.0, 1.0, 41)  # 0.025 rad per sample
    fine = np.zeros((161, 6))
    fine[:, 0] = np.linspace(0.0, 1.0, 161)  # 0.00625 rad per sample
    a, b = coarse[checked_indices(coarse, 0.02)], fine[checked_indices(fine, 0.02)]
    assert np.abs(np.diff(a[:, 0])).max() <= 0.025 + 1e-12 and np.abs(np.diff(b[:, 0])).max() <= 0.025 + 1e-12
    assert abs(len(a) - len(b)) <= 8 and len(b) >= 1.0 / 0.025
