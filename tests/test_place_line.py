"""The line onto the peg: placed clear of it, a direction the object's points clear it on."""
import numpy as np
import pytest

from app.motion.place_line import _fixture_scene, above_peg, directions, hits, peg_line_direction
from app.objects import fixture
from hardware.se3 import make_pose, rotvec_to_matrix

RACK = fixture("rack").landmarks
A = np.asarray(RACK["approach"], float)


def test_above_peg_moves_the_fixture_along_the_pegs_upward_normal():
    T = make_pose(rotvec_to_matrix([0.0, 0.0, np.pi]), [0.55, 0.40, 0.0])
    moved = above_peg(T, "rack", 0.006)
    d = T[:3, :3].T @ (moved[:3, 3] - T[:3, 3])  # the move in the fixture's frame
    assert np.linalg.norm(d) == pytest.approx(0.006) and abs(d @ A) < 1e-12 and d[2] > 0
    assert np.array_equal(moved[:3, :3], T[:3, :3])
    assert np.array_equal(above_peg(T, "shelf", 0.006), T)  # no peg, nothing to clear


def test_short_of_the_hang_moves_the_fixture_out_along_the_peg_towards_its_tip():
    T = make_pose(rotvec_to_matrix([0.0, 0.0, np.pi]), [0.55, 0.40, 0.0])
    d = T[:3, :3].T @ (above_peg(T, "rack", 0.006, short=0.01)[:3, 3] - T[:3, 3])  # fixture frame
    assert d @ A == pytest.approx(0.01) and np.linalg.norm(d - (d @ A) * A) == pytest.approx(0.006)
    tip, root = np.asarray(RACK["peg_tip"]), np.asarray(RACK["peg_origin"])
    assert np.linalg.norm(tip - (root + d)) < np.linalg.norm(tip - root)  # nearer the tip


def test_directions_start_with_the_approach_and_tilt_about_it():
    ds = directions(A)
    assert np.allclose(ds[0], A) and np.allclose(np.linalg.norm(ds, axis=1), 1.0)
    tilts = np.degrees(np.arccos(np.clip(ds[1:] @ A, -1, 1)))
    assert np.allclose(sorted(set(np.round(tilts, 6))), [10.0, 20.0, 30.0, 40.0])


def _peg_frame():
    origin, tip = np.asarray(RACK["peg_origin"]), np.asarray(RACK["peg_tip"])
    up = np.array([0.0, 0.0, 1.0]) - A[2] * A  # the peg's upward normal (towards the post's side)
    return origin + 0.5 * (tip - origin), up / np.linalg.norm(up)


def test_points_around_the_peg_clear_it_along_the_peg_but_not_across_it():
    middle, up = _peg_frame()
    ring = middle + (RACK["peg_radius"] + 0.004) * up  # a handle's inner top, 4 mm over the peg
    scene = _fixture_scene("rack")
    assert hits(ring[None], A, scene, 0.10, 0.001) == 0  # slid out along the peg: never touches it
    assert hits(ring[None], np.array([0.0, 1.0, 0.0]), scene, 0.10, 0.001) == 0  # sideways off it: free
    assert hits(ring[None], -up, scene, 0.10, 0.001) > 0  # pushed down through it: caught
    assert hits(ring[None], up, scene, 0.10, 0.001) > 0  # and up, the way to the post: caught too


def test_points_resting_in_the_peg_get_a_tilted_line_that_leaves_it():
    middle, up = _peg_frame()
    resting = middle + (RACK["peg_radius"] - 0.002) * up  # 2 mm into the peg: the oracle's hangs overlap it so
    scene = _fixture_scene("rack")
    assert hits(resting[None], A, scene, 0.10, 0.001) > 0  # along the peg it stays in it
    d = peg_line_direction(resting[None], np.eye(4), "rack", 0.10)
    assert not np.allclose(d, A) and hits(resting[None], d, scene, 0.10, 0.001) == 0
    clear = middle + (RACK["peg_radius"] + 0.004) * up
    assert np.allclose(peg_line_direction(clear[None], np.eye(4), "rack", 0.10), A)  # kept when it clears
    assert np.allclose(peg_line_direction(resting[None], np.eye(4), "shelf", 0.10),
                       fixture("shelf").landmarks["approach"])  # no peg: the shelf's own approach
