"""The job's own camera check after the release: new pixels must gather where the object was sent."""
import numpy as np

from app.jobs.check import new_points, sighting
from hardware.interfaces import CameraIntrinsics, Frame

K = CameraIntrinsics(width=64, height=48, fx=50.0, fy=50.0, cx=32.0, cy=24.0)


def _frame(depth: np.ndarray) -> Frame:
    return Frame(np.zeros((*depth.shape, 3), np.uint8), depth.astype(np.float32), K, 0.0)


def _scene():
    """A wall 2 m away, then a 12 x 12 pixel patch 1 m away (the object on its fixture)."""
    before = np.full((48, 64), 2.0)
    after = before.copy()
    after[18:30, 26:38] = 1.0
    return _frame(before), _frame(after)


def test_new_pixels_back_project_to_the_patch_in_the_base_frame():
    before, after = _scene()
    T_base_cam = np.eye(4)
    T_base_cam[:3, 3] = [0.1, 0.2, 0.3]
    pts = new_points(before, after, T_base_cam, 0.02)
    assert len(pts) == 144
    np.testing.assert_allclose(pts[:, 2], 1.3)  # depth 1 m along z, then the camera's offset
    u, v = 26 + np.arange(12), 18 + np.arange(12)
    np.testing.assert_allclose(np.sort(np.unique(pts[:, 0].round(6))), ((u - 32) / 50 + 0.1).round(6))
    np.testing.assert_allclose(np.sort(np.unique(pts[:, 1].round(6))), ((v - 24) / 50 + 0.2).round(6))
    assert len(new_points(before, before, T_base_cam, 0.02)) == 0


def test_placed_where_the_patch_is_and_not_placed_elsewhere_or_when_nothing_changed():
    before, after = _scene()
    T = np.eye(4)
    there = new_points(before, after, T, 0.02)
    assert sighting(before, after, T, there).placed()
    assert not sighting(before, after, T, there + [0.5, 0.0, 0.0]).placed()  # sent 50 cm aside: nothing new there
    seen = sighting(before, before, T, there)
    ok, why = seen.placed(), seen.why()
    assert not ok and why.startswith("0 new points")


def test_a_crowded_ball_is_not_placed_but_not_absent_either():
    """New points beside the patch (a mug swinging by the rack) fail the share test; the patch itself
    is still there, so the job does not look for the object elsewhere (`Sighting.absent`)."""
    before, after = _scene()
    T = np.eye(4)
    there = new_points(before, after, T, 0.02)
    after.depth[8:40, 42:50] = 1.0  # a second patch, 0.21-0.5 m from the first one's centre
    seen = sighting(before, after, T, there)
    assert seen.inside == 144 and seen.around > 2 * 144  # the first patch alone in the ball, more beside it
    assert not seen.placed() and not seen.absent()
    assert sighting(before, after, T, there + [2.0, 0.0, 0.0]).absent()  # sent 2 m aside: nothing new there
