"""Grasps turned about a body of revolution's axis keep the task: same place pose, same rim."""
import numpy as np

from app.predict.pairs import Candidate
from app.predict.turned_grasps import slice_centre, turned_pairs
from hardware.se3 import make_pose

AXIS, RADIUS = np.array([0.5, 0.0]), 0.03


def _half_cylinder(n: int = 4000) -> np.ndarray:
    """The half of an upright cylinder (radius 3 cm, 20 cm tall) a camera on +x sees, (n, 3)."""
    rng = np.random.default_rng(0)
    a, z = rng.uniform(-np.pi / 2, np.pi / 2, n), rng.uniform(0.0, 0.2, n)
    return np.column_stack([AXIS[0] + RADIUS * np.cos(a), AXIS[1] + RADIUS * np.sin(a), z])


def _rim_grasp() -> Candidate:
    """From above onto the rim at azimuth 0, the fingers closing radially (tool y along the base's x)."""
    R = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])  # columns: tool x, y, z (down)
    seen = make_pose(t=[0.3, -0.4, 0.1])
    return Candidate(make_pose(R, [AXIS[0] + RADIUS, 0.0, 0.19]), seen, make_pose(t=[0.5, -0.45, 0.2]))


def test_the_slice_centre_is_the_axis_where_the_centroid_is_not():
    cloud = _half_cylinder()
    centre = slice_centre(cloud, 0.19)
    assert np.linalg.norm(centre - AXIS) < 0.001
    assert np.linalg.norm(cloud[:, :2].mean(axis=0) - AXIS) > 0.015  # one side seen: the centroid is off
    assert slice_centre(cloud, 0.5) is None  # above the object: nothing to fit


def test_a_turned_grasp_keeps_the_place_and_the_rim_and_one_on_the_unseen_side_is_dropped():
    cloud, c = _half_cylinder(), _rim_grasp()
    turned = turned_pairs([c], cloud, turns=(60.0, 180.0))
    assert len(turned) == 1  # 180 degrees puts the fingers on the side the camera did not see
    t = turned[0]
    assert np.allclose(t.T_base_tcp_place, c.T_base_tcp_place, atol=1e-9)  # the same place pose
    p = t.T_base_tcp[:3, 3]
    assert abs(np.linalg.norm(p[:2] - AXIS) - RADIUS) < 0.001 and abs(p[2] - 0.19) < 1e-9  # on the rim
    azimuth = np.degrees(np.arctan2(p[1] - AXIS[1], p[0] - AXIS[0]))
    assert abs(azimuth - 60.0) < 1.0
