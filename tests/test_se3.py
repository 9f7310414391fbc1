import numpy as np
import pytest

from hardware import se3


def test_invert_compose_round_trip(rng):
    T = se3.random_poses(20, rng, translation_scale=2.0)
    for Ti in T:
        assert np.allclose(se3.compose(Ti, se3.invert(Ti)), np.eye(4), atol=1e-12)
    assert np.allclose(se3.invert(T) @ T, np.eye(4), atol=1e-12)  # batched


def test_ur_pose_round_trip_and_known_value(rng):
    for T in se3.random_poses(20, rng, translation_scale=1.0):
        assert np.allclose(se3.ur_to_pose(se3.pose_to_ur(T)), T, atol=1e-12)
    quarter_turn_z = se3.ur_to_pose([1, 2, 3, 0, 0, np.pi / 2])
    assert np.allclose(quarter_turn_z[:3, :3] @ [1, 0, 0], [0, 1, 0])
    assert np.allclose(quarter_turn_z[:3, 3], [1, 2, 3])
    with pytest.raises(ValueError, match="6 values"):
        se3.ur_to_pose([1, 2, 3])


def test_rotation_vector_near_pi_is_stable():
    R = se3.rotvec_to_matrix([0.0, 0.0, np.pi - 1e-9])
    assert np.isclose(se3.rotation_angle(R), np.pi, atol=1e-6)


def test_haar_rotations_are_uniform(rng):
    R = se3.random_rotations(20000, rng)
    assert np.allclose(R @ R.transpose(0, 2, 1), np.eye(3), atol=1e-10)
    assert np.allclose(np.linalg.det(R), 1.0)
    assert np.abs(R.mean(axis=0)).max() < 0.02  # E[R] = 0 under the Haar measure
    # the angle density of a uniform rotation is (1 - cos a) / pi, mean = pi/2 + 2/pi
    assert np.isclose(se3.rotation_angle(R).mean(), np.pi / 2 + 2 / np.pi, atol=0.02)


def test_transform_points_and_pose_error(rng):
    T = se3.random_poses(1, rng, translation_scale=1.0)[0]
    p = rng.normal(size=(5, 3))
    assert np.allclose(se3.transform_points(se3.invert(T), se3.transform_points(T, p)), p)
    dt, dr = se3.pose_error(T, T @ se3.make_pose(se3.rotvec_to_matrix([0.1, 0, 0]), [0, 0.02, 0]))
    assert np.isclose(dt, 0.02) and np.isclose(dr, 0.1)


def test_interpolated_pose_is_scipy_slerp_and_lerp(rng):
    """Halfway and at random s the rotation is scipy's Slerp of the two ends; the ends are exact."""
    from scipy.spatial.transform import Rotation, Slerp

    for _ in range(50):
        R0, R1 = Rotation.random(2, random_state=rng.integers(1 << 31)).as_matrix()
        T0, T1 = se3.make_pose(R0, rng.normal(size=3)), se3.make_pose(R1, rng.normal(size=3))
        s = float(rng.uniform())
        T = se3.interpolate_pose(T0, T1, s)
        assert np.allclose(T[:3, :3], Slerp([0.0, 1.0], Rotation.from_matrix([R0, R1]))(s).as_matrix(), atol=1e-9)
        assert np.allclose(T[:3, 3], (1 - s) * T0[:3, 3] + s * T1[:3, 3])
        assert np.allclose(se3.interpolate_pose(T0, T1, 0.0), T0) and np.allclose(se3.interpolate_pose(T0, T1, 1.0), T1)


def test_pybullet_pose_conversion_round_trips_and_matches_scipy(rng):
    from scipy.spatial.transform import Rotation

    from hardware.bullet import pose_to_pybullet, pybullet_to_pose

    for T in se3.random_poses(50, rng, translation_scale=1.0):
        position, quaternion = pose_to_pybullet(T)
        assert np.allclose(pybullet_to_pose(position, quaternion), T, atol=1e-12)
        expected = Rotation.from_matrix(T[:3, :3]).as_quat()
        assert min(np.abs(quaternion - expected).max(), np.abs(quaternion + expected).max()) < 1e-12
    nearly = se3.random_poses(1, rng)[0].astype(np.float32).astype(np.float64)  # not a rotation to 1e-9
    nearly[:3, :3] *= 1.0 + 1e-6
    _, quaternion = pose_to_pybullet(nearly)
    assert abs(np.linalg.norm(quaternion) - 1.0) < 1e-12
    assert np.allclose(pybullet_to_pose([0, 0, 0], quaternion)[:3, :3], nearly[:3, :3], atol=1e-5)
    for T in se3.random_poses(20, rng):  # float32 poses (a held object's), off a rotation by ~1e-7: Eigen's path
        single = T.astype(np.float32).astype(np.float64)
        _, quaternion = pose_to_pybullet(single)
        expected = Rotation.from_matrix(single[:3, :3]).as_quat()  # SciPy's nearest rotation
        assert abs(np.linalg.norm(quaternion) - 1.0) < 1e-12
        assert min(np.abs(quaternion - expected).max(), np.abs(quaternion + expected).max()) < 1e-6
