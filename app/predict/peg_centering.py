"""Centre a predicted hang on the peg: the peg must run through free space in the object's cloud.

Our addition (not in the paper), the place's counterpart of `app.predict.grasp_centering`. On the rack the
imitated pose pins the mug's handle hole well across the hole (a few millimetres) but poorly along
its long axis: the hole is 3-6 cm long there and the field's features change slowly along it, so the
hole's centre ended 15-35 mm off the peg in most failed hangs (`scripts/diagnose/diagnose_peg_centering.py`).
The cloud shows where the hole is: in the fixture's frame, with the peg from origin o along d, the
"up" direction across it e_1 (world z minus its part along d) and e_2 = d x e_1, take the cloud
points in the peg's lane - along the peg, level with its axis, within reach:

    L = { p : 0 < (p - o).d < peg length,  |(p - o).e_1| < LANE,  |(p - o).e_2| < REACH }

sort their coordinates v = (p - o).e_2, and move the object along e_2 so that the peg sits in the
middle of the gap between consecutive v's that is wide enough for the peg (2 r + CLEARANCE) and
nearest to where the peg is now. No such gap (or fewer than 2 points in the lane): the pose is left
as it is. Fixtures without a peg (the shelf) are left alone.
"""
from __future__ import annotations

import numpy as np

from app.objects import Fixture
from hardware.se3 import invert, make_pose, transform_points

LANE = 0.004  # metres: half-height of the lane level with the peg's axis
REACH = 0.06  # metres: how far along e_2 the lane reaches either side of the peg
CLEARANCE = 0.004  # metres: a gap must be the peg's diameter plus this


def peg_frame(fx: Fixture) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(o, d, e_1, e_2) of a fixture's peg, fixture frame: origin, axis, up across it, sideways."""
    o, d = np.array(fx.landmarks["peg_origin"]), np.array(fx.landmarks["peg_direction"])
    e1 = np.array([0.0, 0.0, 1.0]) - d[2] * d
    e1 /= np.linalg.norm(e1)
    return o, d, e1, np.cross(d, e1)


def peg_shift(cloud_fixture: np.ndarray, fx: Fixture) -> float:
    """How far (metres, along e_2) the peg must move, relative to the cloud (N, 3) in the fixture's
    frame, to sit in the middle of the nearest gap it fits through; 0 when there is none."""
    o, d, e1, e2 = peg_frame(fx)
    q = np.asarray(cloud_fixture, float) - o  # (N, 3)
    s, u, v = q @ d, q @ e1, q @ e2
    lane = np.sort(v[(s > 0) & (s < fx.landmarks["peg_length"]) & (np.abs(u) < LANE) & (np.abs(v) < REACH)])
    if len(lane) < 2:
        return 0.0
    gaps, mids = np.diff(lane), (lane[:-1] + lane[1:]) / 2  # (K-1,)
    wide = gaps > 2 * fx.landmarks["peg_radius"] + CLEARANCE
    if not wide.any():
        return 0.0
    return float(mids[wide][np.argmin(np.abs(mids[wide]))])


def center_on_peg(T_base_fixture_seen: np.ndarray, cloud: np.ndarray, fx: Fixture) -> np.ndarray:
    """T_base_fixture_seen (the fixture's pose relative to the cloud (N, 3), base frame) moved along
    its peg's e_2 so the peg runs through the middle of the hole's gap; unchanged without a peg."""
    if "peg_origin" not in fx.landmarks:
        return T_base_fixture_seen.copy()
    shift = peg_shift(transform_points(invert(T_base_fixture_seen), cloud), fx)
    return T_base_fixture_seen @ make_pose(np.eye(3), shift * peg_frame(fx)[3])
