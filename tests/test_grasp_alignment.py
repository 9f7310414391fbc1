"""Grasp alignment: the turn onto a wall's normal (analytic), what it leaves alone, and the slip it mends."""
import numpy as np
import pytest

from app.predict.grasp_alignment import MAX_ANGLE, align_grasp, surface_normals, wall_direction
from app.predict.grasp_centering import MIN_POINTS, center_grasp
from hardware.se3 import make_pose, random_rotations, rotvec_to_matrix, transform_points


def _pose(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return make_pose(random_rotations(1, rng)[0], rng.uniform(-0.5, 0.5, 3))


def _wall(tilt_deg: float, n: int = 600, thickness: float = 0.0, seed: int = 0) -> np.ndarray:
    """Points (n, 3), TCP frame, on the faces of a wall through the TCP whose normal is the closing
    axis y turned by `tilt_deg` about the finger-width axis x."""
    rng = np.random.default_rng(seed)
    u, v = rng.uniform(-0.02, 0.02, n), rng.uniform(-0.03, 0.03, n)  # in the wall's plane
    side = np.where(rng.random(n) < 0.5, -thickness / 2, thickness / 2)
    flat = np.column_stack([u, side, v])  # wall normal along y
    return flat @ rotvec_to_matrix([np.radians(tilt_deg), 0.0, 0.0]).T


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip(abs(a @ b), -1.0, 1.0))))


@pytest.mark.parametrize("tilt", [8.0, 20.0, 35.0])
def test_the_closing_axis_ends_up_along_the_walls_normal(tilt):
    T = _pose(int(tilt))
    cloud = transform_points(T, _wall(tilt))
    normal = T[:3, :3] @ rotvec_to_matrix([np.radians(tilt), 0.0, 0.0])[:, 1]  # base frame
    out = align_grasp(T, cloud)
    assert _angle(out[:3, 1], normal) < 1.5  # Open3D's normals of a noise-free wall
    np.testing.assert_allclose(out[:3, 3], T[:3, 3])  # turned about the TCP
    turn = np.degrees(np.arccos(np.clip((np.trace(T[:3, :3].T @ out[:3, :3]) - 1) / 2, -1, 1)))
    assert abs(turn - tilt) < 1.5  # the smallest rotation: no spin about the normal
    np.testing.assert_allclose(out[:3, :3] @ out[:3, :3].T, np.eye(3), atol=1e-9)


def test_wall_direction_is_the_axis_most_parallel_to_the_normals():
    rng = np.random.default_rng(0)
    axis = np.array([0.6, 0.0, 0.8])
    normals = axis + rng.normal(0, 0.05, (200, 3))
    normals *= np.where(rng.random(200) < 0.5, -1.0, 1.0)[:, None]  # signs arbitrary, as from PCA
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    assert _angle(wall_direction(normals), axis) < 1.0


def test_a_square_grasp_few_points_and_large_turns_are_left_alone():
    T = _pose(1)
    square = align_grasp(T, transform_points(T, _wall(0.0)))
    assert _angle(square[:3, 1], T[:3, 1]) < 1.5
    few = transform_points(T, _wall(20.0, n=MIN_POINTS - 1))
    np.testing.assert_array_equal(align_grasp(T, few, normals=np.tile(T[:3, 2], (len(few), 1))), T)
    steep = transform_points(T, _wall(np.degrees(MAX_ANGLE) + 15.0))
    np.testing.assert_array_equal(align_grasp(T, steep), T)
    tilted = transform_points(T, _wall(20.0))
    unknown = np.full_like(tilted, np.nan)  # no usable normal anywhere
    np.testing.assert_array_equal(align_grasp(T, tilted, normals=unknown), T)


def test_given_normals_are_used_and_match_open3d():
    T = _pose(2)
    cloud = transform_points(T, _wall(15.0))
    normals = surface_normals(cloud)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-9)
    np.testing.assert_allclose(align_grasp(T, cloud, normals), align_grasp(T, cloud))


@pytest.mark.parametrize("category, tilt", [("bowl", 25.0), ("mug", 15.0)])
def test_a_rim_grasp_tilted_across_the_wall_slips_and_aligned_holds(category, tilt, teacher_grasp_verdicts):
    """The teacher's rim grasp turned about the finger-width axis touches the wall with pad edges and
    slips on the lift; turned back onto the wall's normal (then centred, as predictions are) it holds."""
    from app.predict.predict import refine_grasp

    turned = make_pose(rotvec_to_matrix([np.radians(tilt), 0.0, 0.0]))
    centred, aligned = teacher_grasp_verdicts(category, turned, [
        lambda T, cloud: refine_grasp(T, cloud, center=True, align=False),
        lambda T, cloud: refine_grasp(T, cloud, center=True, align=True)])
    assert not centred.success, centred.reason
    assert aligned.success, aligned.reason


def test_predictions_are_turned_then_centred_and_an_unturned_grasp_is_centred_once():
    from app.predict.predict import refine_grasp

    T = _pose(6)
    beyond = _wall(0.0, n=100, seed=1) * [0.5, 1.0, 0.5] + [0.0, 0.045, 0.0]  # just past the open fingers
    square = transform_points(T, np.vstack([_wall(0.0) + [0.0, 0.006, 0.0], beyond]))  # off-centre, square
    assert not np.array_equal(center_grasp(center_grasp(T, square), square), center_grasp(T, square))  # reached once moved
    np.testing.assert_array_equal(refine_grasp(T, square, center=True, align=True), center_grasp(T, square))
    np.testing.assert_array_equal(refine_grasp(T, square, center=False, align=False), T)
    tilted = transform_points(T, _wall(20.0) + [0.0, 0.006, 0.0])
    out = refine_grasp(T, tilted, center=True, align=True)
    normal = T[:3, :3] @ rotvec_to_matrix([np.radians(20.0), 0.0, 0.0])[:, 1]
    assert _angle(out[:3, 1], normal) < 1.5
    seen = (tilted - out[:3, 3]) @ out[:3, :3]  # TCP frame: the wall's middle along y is at the TCP
    assert abs(np.median(seen[:, 1])) < 1e-3
