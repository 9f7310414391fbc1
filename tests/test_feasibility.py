"""Feasibility of imitated poses: the predicates on known geometry, and imitation honouring a predicate."""
import numpy as np

from app.predict.feasibility import (GRIP_POINTS, all_of, carries_like_demos, grip_points, grips_something,
                                     point_spacing, reaches)
from app.predict.grasp_centering import swept_points
from hardware.se3 import invert, make_pose, random_rotations, rotvec_to_matrix


def test_a_grasp_grips_something_only_with_points_between_the_fingers():
    rng = np.random.default_rng(0)
    T = make_pose(random_rotations(1, rng)[0], [0.4, 0.1, 0.2])
    wall = rng.uniform([-0.005, -0.004, -0.01], [0.005, 0.004, 0.01], size=(200, 3))  # a slab at the TCP
    cloud = wall @ T[:3, :3].T + T[:3, 3]
    away = T @ make_pose(np.eye(3), [0.0, 0.0, -0.10])  # 10 cm back along the approach: fingers in the air
    sideways = T @ make_pose(np.eye(3), [0.10, 0.0, 0.0])  # beside the fingers
    assert grips_something(cloud)(np.stack([T, away, sideways])).tolist() == [True, False, False]
    few = cloud[:GRIP_POINTS - 1]
    assert not grips_something(few)(T[None])[0]


def test_a_sparser_cloud_asks_for_fewer_points_between_the_fingers_for_the_same_surface():
    """Grid clouds: spacing 2 mm and 4 mm keep the 20-point rule, 8 mm asks for a quarter of it."""
    for spacing, need in ((0.002, GRIP_POINTS), (0.004, GRIP_POINTS), (0.008, GRIP_POINTS // 4)):
        u = np.arange(0, 0.2, spacing)
        grid = np.stack(np.meshgrid(u, u, [0.0]), -1).reshape(-1, 3)
        assert abs(point_spacing(np.concatenate([grid, grid])) - spacing) < 1e-9  # repeated points do not count
        assert grip_points(grid) == need
    # a wall between the fingers (the TCP frame's x-z plane) at 8 mm spacing: fewer points than the
    # dense rule asks, enough for the sparse one
    T = make_pose(random_rotations(1, np.random.default_rng(2))[0], [0.4, 0.1, 0.2])
    u = np.arange(-0.1, 0.1, 0.008)
    wall = np.stack(np.meshgrid(u, [0.0], u), -1).reshape(-1, 3) @ T[:3, :3].T + T[:3, 3]
    between = len(swept_points(T, wall))
    assert grip_points(wall) <= between < GRIP_POINTS
    assert grips_something(wall)(T[None])[0]
    assert not grips_something(wall, min_points=4 * GRIP_POINTS)(T[None])[0]


def test_a_place_that_turns_the_object_over_relative_to_the_grasp_is_not_carried_like_the_demos():
    """A bottle held at its neck, 17 cm above its base: the demos set it on the shelf with the TCP 17 cm
    above the fixture; the same place turned over puts the TCP 17 cm lower than the object's top."""
    T_obj_tcp = make_pose(np.eye(3), [0.0, 0.0, 0.17])  # the grasp, in the object's frame
    T_fixture_obj = make_pose(np.eye(3), [0.0, 0.0, 0.003])  # upright on the board
    demos = [T_fixture_obj @ T_obj_tcp]  # each demo's T_fixture_tcp
    T_base_obj = make_pose(random_rotations(1, np.random.default_rng(1))[0], [0.5, 0.0, 0.3])
    T_base_tcp = T_base_obj @ T_obj_tcp
    upright = T_base_obj @ invert(T_fixture_obj)  # T_base_fixture_seen of the demo's place
    yawed = T_base_obj @ invert(make_pose(rotvec_to_matrix([0, 0, 2.0]), [0.05, -0.03, 0.003]))  # elsewhere on the board
    flip = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.0, 0.0, 0.22])  # upside down, top (22 cm) on the board
    over = T_base_obj @ invert(flip)
    assert carries_like_demos(T_base_tcp, demos)(np.stack([upright, yawed, over])).tolist() == [True, True, False]


def test_reaches_asks_each_grasp_and_all_of_joins_predicates():
    """The cell can put its gripper at TCP heights above 0.2 m only (a stand-in for its clearance test)."""
    reachable = lambda T: T[2, 3] > 0.2  # noqa: E731
    assert reaches(reachable)(np.stack([make_pose(t=[0.5, 0.0, 0.3]), make_pose(t=[0.5, 0.0, 0.1])])).tolist() == [True, False]
    both = all_of(reaches(reachable), None, lambda poses: poses[:, 0, 3] > 0.45)
    poses = np.stack([make_pose(t=[0.5, 0.0, 0.3]), make_pose(t=[0.4, 0.0, 0.3]), make_pose(t=[0.5, 0.0, 0.1])])
    assert both(poses).tolist() == [True, False, False]
    assert all_of(None, None) is None
