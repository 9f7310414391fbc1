"""Grasp centring: the analytic shift, what it ignores, and the physical outcome it is for."""
import numpy as np
import pytest

from app.predict.grasp_centering import MIN_POINTS, center_grasp, held_width, swept_points
from hardware.gripper_geometry import GripperGeometry
from hardware.se3 import make_pose, random_rotations, transform_points


def _pose(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return make_pose(random_rotations(1, rng)[0], rng.uniform(-0.5, 0.5, 3))


def _slab(y0: float, y1: float, n: int = 200, seed: int = 0) -> np.ndarray:
    """Points (n, 3), TCP frame, of a wall between y0 and y1 inside the fingers' reach."""
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-0.01, 0.01, n), rng.uniform(y0, y1, n), rng.uniform(-0.03, 0.015, n)])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_wall_off_centre_ends_up_between_the_fingers(seed):
    T = _pose(seed)
    wall = _slab(0.006, 0.010, seed=seed)
    out = center_grasp(T, transform_points(T, wall))
    np.testing.assert_allclose(out[:3, :3], T[:3, :3])  # only moved, along the closing axis
    seen = swept_points(out, transform_points(T, wall))
    middle = (seen[:, 1].min() + seen[:, 1].max()) / 2
    assert abs(middle) < 1e-9
    shift = np.linalg.inv(T) @ out
    np.testing.assert_allclose(shift[:3, 3], [0.0, (wall[:, 1].min() + wall[:, 1].max()) / 2, 0.0], atol=1e-12)


def test_points_the_fingers_cannot_reach_are_ignored():
    T = _pose(3)
    g = GripperGeometry()
    wall = _slab(-0.004, 0.0)
    beyond = np.array([[0.0, 0.03, 0.05],  # past the fingertips
                       [0.02, 0.03, 0.0],  # beside the fingers (x over half their width)
                       [0.0, g.stroke, 0.0]])  # outside the open fingers
    alone = center_grasp(T, transform_points(T, wall))
    with_far = center_grasp(T, transform_points(T, np.vstack([wall, beyond])))
    np.testing.assert_allclose(with_far, alone)


def test_too_few_points_leave_the_grasp_as_it_is():
    T = _pose(4)
    few = transform_points(T, _slab(0.01, 0.02, n=MIN_POINTS - 1))
    np.testing.assert_array_equal(center_grasp(T, few), T)
    np.testing.assert_array_equal(center_grasp(T, np.empty((0, 3))), T)


def test_a_centred_wall_is_not_moved():
    T = _pose(5)
    wall = _slab(-0.003, 0.003)
    wall[:2, 1] = [-0.003, 0.003]  # exact extremes
    np.testing.assert_allclose(center_grasp(T, transform_points(T, wall)), T, atol=1e-12)


def test_a_bowl_grasp_8mm_off_the_wall_fails_and_centred_holds(teacher_grasp_verdicts):
    """The teleported judge holds the bowl while the fingers close: 8 mm off, one finger misses."""
    off = make_pose(np.eye(3), [0.0, -0.008, 0.0])  # away from the axis
    as_is, centred = teacher_grasp_verdicts("bowl", off, [lambda T, cloud: T, center_grasp])
    assert not as_is.success, as_is.reason
    assert centred.success, centred.reason


@pytest.mark.parametrize("seed", [0, 1])
def test_the_held_width_is_the_walls_thickness_plus_the_margin_and_the_stroke_without_points(seed):
    T = _pose(seed)
    wall = _slab(0.006, 0.010, seed=seed)  # 4 mm thick
    width = held_width(T, transform_points(T, wall), margin=0.015)
    assert abs(width - (np.ptp(wall[:, 1]) + 0.015)) < 1e-12 and 0.018 < width <= 0.019
    assert held_width(T, transform_points(T, _slab(-0.04, 0.04, n=400))) == GripperGeometry().stroke  # clipped
    assert held_width(T, transform_points(T, wall[: MIN_POINTS - 1])) == GripperGeometry().stroke


def _rim_beside_the_fingers(seed: int) -> np.ndarray:
    """Points (N, 3), TCP frame, of a 5 mm rim of radius 4 cm curving away from the TCP, seen only
    13-24 mm beside the fingers' middle (the part under the fingers hidden)."""
    rng = np.random.default_rng(seed)
    x = rng.choice([-1, 1], 300) * rng.uniform(0.013, 0.024, 300)
    r = 0.04 + rng.uniform(-0.0025, 0.0025, 300)  # across the wall
    y = 0.04 - np.sqrt(r**2 - x**2)  # the rim's centre line passes through the TCP
    return np.column_stack([x, y, rng.uniform(-0.02, 0.01, 300)])


@pytest.mark.parametrize("seed", [0, 1])
def test_a_hidden_rim_is_measured_beside_the_fingers_and_a_far_wall_is_not_held(seed):
    T = _pose(seed)
    rim = _rim_beside_the_fingers(seed)
    assert len(swept_points(T, transform_points(T, rim))) == 0  # nothing between the fingers
    width = held_width(T, transform_points(T, rim), margin=0.015)
    assert 0.015 + 0.005 <= width <= 0.015 + 0.005 + 0.004  # the wall (5 mm) and the curve within one slice
    far_wall = _slab(0.036, 0.040, n=40, seed=seed) * [0.5, 1.0, 1.0] + [0.019, 0.0, 0.0]  # beside the fingers too
    assert held_width(T, transform_points(T, np.vstack([rim, far_wall])), margin=0.015) == width
    assert held_width(T, transform_points(T, rim + [0.0, 0.0, 0.05])) == GripperGeometry().stroke  # past the fingertips
