"""Grasps turned about a body of revolution's axis (our addition): the same task at another point of
the rim or the neck, for when none of the imitated pairs can be planned.

A bowl or a bottle standing upright is the same shape turned about its vertical axis, so a grasp G
turned by A (a rotation about that axis) holds it as well, and the pair keeps its place: with the
fixture as seen turned too (seen' = A seen), the object's motion becomes motion A^-1 and the TCP at
the place  motion A^-1 A G = motion G  is the same pose - the object arrives turned about its own
axis, which does not matter. The axis is where the cloud's slice at the grasp's height is centred
(a circle fitted to the slice, `app.predict.handle_hole.kasa_circle`: one Kinect sees an arc, whose centroid would lie
towards the camera); a turned grasp that no longer closes on the cloud is dropped.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from app.predict.pairs import Candidate
from app.predict.feasibility import grips_something
from app.predict.handle_hole import kasa_circle
from hardware.se3 import make_pose, rotvec_to_matrix

TURNS_DEG = (60.0, -60.0, 120.0, -120.0, 180.0)  # nearest first
SLICE = 0.01  # m above and below the grasp's height
MIN_SLICE_POINTS = 20
RADIUS_RANGE = (0.005, 0.15)  # m: a slice fitted outside this is not a body of revolution's


def slice_centre(cloud: np.ndarray, z: float) -> np.ndarray | None:
    """(2,) centre of the circle fitted to the cloud's points (N, 3) within SLICE of height z; None
    when too few points or a radius outside RADIUS_RANGE."""
    ring = cloud[np.abs(cloud[:, 2] - z) < SLICE][:, :2]  # (M, 2)
    if len(ring) < MIN_SLICE_POINTS:
        return None
    centre, radius = kasa_circle(ring)
    return centre if RADIUS_RANGE[0] <= radius <= RADIUS_RANGE[1] else None


def about_vertical(centre: np.ndarray, degrees: float) -> np.ndarray:
    """(4, 4) the rotation by `degrees` about the vertical line through the point (2,) `centre`."""
    c = np.array([centre[0], centre[1], 0.0])
    R = rotvec_to_matrix([0.0, 0.0, np.radians(degrees)])
    return make_pose(R, c - R @ c)


def turned_pairs(options: list[Candidate], cloud: np.ndarray,
                 turns: tuple[float, ...] = TURNS_DEG) -> list[Candidate]:
    """Each distinct grasp's first pair (by grasp_rank) turned by `turns` about the axis at its height,
    those that still close on the cloud, in the options' order."""
    pairs, seen = [], set()
    for c in options:
        if c.grasp_rank in seen:
            continue
        seen.add(c.grasp_rank)
        centre = slice_centre(cloud, float(c.T_base_tcp[2, 3]))
        if centre is None:
            continue
        for degrees in turns:
            A = about_vertical(centre, degrees)
            pairs.append(replace(c, T_base_tcp=A @ c.T_base_tcp, T_base_fixture_seen=A @ c.T_base_fixture_seen))
    if not pairs:
        return []
    closes = grips_something(cloud)(np.stack([c.T_base_tcp for c in pairs]))
    return [c for c, ok in zip(pairs, closes) if ok]
