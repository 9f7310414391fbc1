"""The job's own check that the object ended on the fixture, from its camera alone (our addition).

The Kinect is fixed, so the job's first frame is a picture of the fixture without the object. After
the release, with the arm home again, a second frame is compared with it pixel by pixel: pixels
that came at least `closer` nearer to the camera show something new. Back-projected into the base
frame, they should gather where the object was sent: the observed cloud moved by the place motion,
X' = M X, with centroid c and radius r (its farthest point from c). With n(R) the new points
within R of c,

    placed  <=>  n(r + slack) >= min_points  and  n(r + slack) >= share * n(2 (r + slack))

The object's unseen back and a mug that swings on its peg put new points centimetres from X'
itself, so the test is the ball, not the points. An object that fell to the table or the floor
makes new points outside it (or none there); further away the Kinect's noise makes new pixels of
its own (1,400 on the floor 3 m off between two frames of a still scene), which the outer ball
leaves out. The simulator's own judge stays the benchmark's verdict; this is what a real cell
can know.

Fewer than `min_points` new points in the ball (`Sighting.absent`) says more: nothing stands where
the object was sent, it fell somewhere else, and the job looks for it again. A mug that hangs but
swings or hides behind the rack fails the share test at times (5 of 39 NIFT resting hangs), never
this one (577 new points or more in the ball).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from hardware.interfaces import Frame
from hardware.se3 import transform_points


@dataclass(frozen=True)
class PlacedCheck:
    """Thresholds of the camera check."""

    closer: float = 0.02  # m nearer the camera than in the first frame: something new (depth noise: a few mm)
    slack: float = 0.03  # m beyond the object's radius
    min_points: int = 100  # new pixels in the ball
    share: float = 0.5  # of the new pixels in the ball of twice its radius


def new_points(before: Frame, after: Frame, T_base_cam: np.ndarray, closer: float) -> np.ndarray:
    """(K, 3) base-frame points of the pixels of `after` at least `closer` nearer than in `before`."""
    d0, d1 = np.asarray(before.depth, float), np.asarray(after.depth, float)  # (H, W) metres, 0 = invalid
    mask = (d1 > 0) & ((d0 <= 0) | (d1 < d0 - closer))
    v, u = np.nonzero(mask)
    z = d1[mask]
    K = after.intrinsics
    cam = np.column_stack([(u - K.cx) * z / K.fx, (v - K.cy) * z / K.fy, z])  # (K, 3) camera frame
    return transform_points(T_base_cam, cam)


@dataclass(frozen=True)
class Sighting:
    """What the camera shows where the object was sent: new points within `radius` (m) of there, and within twice it."""

    inside: int
    around: int
    radius: float

    def placed(self, check: PlacedCheck = PlacedCheck()) -> bool:
        """Enough new points in the ball, and most of those around it."""
        return self.inside >= check.min_points and self.inside >= check.share * self.around

    def absent(self, check: PlacedCheck = PlacedCheck()) -> bool:
        """Too few new points in the ball for anything to stand there: the object is elsewhere. (A hung mug
        that swings, or hides behind the rack, can fail the share test; it never leaves the ball empty.)"""
        return self.inside < check.min_points

    def why(self) -> str:
        return (f"{self.inside} new points within {self.radius:.2f} m of where the object was sent, "
                f"{self.around} within {2 * self.radius:.2f} m")


def sighting(before: Frame, after: Frame, T_base_cam: np.ndarray, expected: np.ndarray,
             check: PlacedCheck = PlacedCheck()) -> Sighting:
    """The new points of `after` counted around where the object was sent (`expected`, (N, 3))."""
    c = expected.mean(axis=0)
    R = float(np.linalg.norm(expected - c, axis=1).max()) + check.slack
    d = np.linalg.norm(new_points(before, after, T_base_cam, check.closer) - c, axis=1)  # (K,)
    return Sighting(int((d < R).sum()), int((d < 2 * R).sum()), R)
