"""Grasps backed off the table: the analytic back-off, and the cases it leaves alone."""
import numpy as np

from app.predict.table_clearance import backed_off_table
from hardware.gripper_geometry import lowest_point
from hardware.se3 import make_pose, rotvec_to_matrix

DOWN = rotvec_to_matrix([np.pi, 0.0, 0.0])  # approach axis straight down


def _wall(z0: float, z1: float, n: int = 400) -> np.ndarray:
    """A 4 mm wall across the fingers' closing axis (base y), at x = 0.5, from z0 to z1."""
    rng = np.random.default_rng(0)
    return np.column_stack([rng.uniform(0.49, 0.51, n), rng.uniform(-0.002, 0.002, n), rng.uniform(z0, z1, n)])


def test_a_grasp_low_on_a_wall_rises_until_the_fingertips_clear_the_table():
    T = make_pose(DOWN, [0.5, 0.0, 0.01])  # fingertips 1 cm into the table
    out = backed_off_table(T, _wall(0.0, 0.08), clearance=0.008)
    assert np.isclose(lowest_point(out), 0.008)
    np.testing.assert_allclose(out[:3, :3], T[:3, :3])
    np.testing.assert_allclose(out[:3, 3], [0.5, 0.0, 0.01 + 0.018], atol=1e-12)  # straight back up its axis


def test_grasps_clear_of_the_table_sideways_too_far_or_closing_on_nothing_are_left_alone():
    wall = _wall(0.0, 0.08)
    high = make_pose(DOWN, [0.5, 0.0, 0.05])
    assert np.array_equal(backed_off_table(high, wall), high)
    sideways = make_pose(rotvec_to_matrix([0.0, np.pi / 2, 0.0]), [0.5, 0.0, 0.04])  # approach along x
    assert np.array_equal(backed_off_table(sideways, wall), sideways)
    deep = make_pose(DOWN, [0.5, 0.0, -0.03])  # would need 5 cm
    assert np.array_equal(backed_off_table(deep, wall), deep)
    short = _wall(0.0, 0.007)  # the wall ends below where the backed-off fingertips reach (8 mm)
    low = make_pose(DOWN, [0.5, 0.0, 0.01])
    assert np.array_equal(backed_off_table(low, short), low)
