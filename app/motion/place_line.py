"""The line onto a peg, chosen so the held object's points clear the fixture (our addition).

A mug hangs by its handle on the rack's peg, which rises at 45 degrees; the place line comes onto
the hang from `place_distances[0]` out along the peg. The planning scene cannot check the carried
object on that line - the hull of its cloud fills the handle, so it always overlaps the peg. The
oracle's hangs have the handle resting in the peg (4-7 of the mesh's vertices inside it); slid
along the peg so, the handle drags on it and turns the mug in the grasp, pushing the fingers apart.
So the object is placed `clearance` above its
hang (`above_peg`), and the peg is what must pass through the handle: the object's points at the
place, moved back along a direction d by s in (0, L],

    x(s) = x + s d,    hit  <=>  signed distance of x(s) to the fixture's mesh < margin,

and the first direction with no hit wins: the fixture's own approach first, then rings of
directions tilted 10-40 degrees about it. Fixtures without a peg (the shelf) keep their approach.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from app.nift.raycast import scene_of, signed_distance
from app.objects import fixture
from hardware.se3 import invert, rotvec_to_matrix, transform_points

TILTS_DEG = (10.0, 20.0, 30.0, 40.0)
AZIMUTHS = 8
STEPS = 20
START = 0.01  # m: the first 1 cm back from the hang is where the handle rests on the peg


@lru_cache(maxsize=4)
def _fixture_scene(name: str):
    return scene_of(fixture(name).mesh)


def directions(approach: np.ndarray) -> np.ndarray:
    """(K, 3) the approach, then rings tilted by TILTS_DEG about it (AZIMUTHS each), unit vectors."""
    a = np.asarray(approach, float) / np.linalg.norm(approach)
    side = np.cross(a, [0.0, 0.0, 1.0] if abs(a[2]) < 0.9 else [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    out = [a]
    for tilt in np.radians(TILTS_DEG):
        for phi in np.linspace(0.0, 2 * np.pi, AZIMUTHS, endpoint=False):
            axis = rotvec_to_matrix(a * phi) @ side
            out.append(rotvec_to_matrix(axis * tilt) @ a)
    return np.array(out)


def hits(points: np.ndarray, direction: np.ndarray, scene, distance: float, margin: float) -> int:
    """How many of the points (N, 3, fixture frame) come within `margin` of the fixture on the line."""
    s = np.linspace(START, distance, STEPS)  # (S,)
    swept = points[None] + s[:, None, None] * direction  # (S, N, 3)
    return int((signed_distance(scene, swept.reshape(-1, 3)) < margin).sum())


def above_peg(T_base_fixture: np.ndarray, fixture_name: str, clearance: float, short: float = 0.0) -> np.ndarray:
    """The fixture's pose moved by `clearance` along the normal of its peg that points most up
    (n = z - (z . a) a, normalised, a the peg's direction) and by `short` out along the peg: an object
    placed for the moved fixture hangs that far above its hang and that far nearer the peg's tip,
    slides along the peg without resting on it, and drops (and slides down the peg) when let go.
    Fixtures without a peg are returned as they are."""
    f = fixture(fixture_name)
    if "peg_tip" not in f.landmarks or (clearance == 0.0 and short == 0.0):
        return T_base_fixture
    a = np.asarray(f.landmarks["approach"], float)
    n = np.array([0.0, 0.0, 1.0]) - a[2] * a
    moved = np.array(T_base_fixture, float)
    moved[:3, 3] += T_base_fixture[:3, :3] @ (clearance * n / np.linalg.norm(n) + short * a)
    return moved


def fixture_approach(T_base_fixture: np.ndarray, fixture_name: str) -> np.ndarray:
    """Unit direction (3,), base frame, of the fixture's own line onto it (along a peg: the peg's axis)."""
    return T_base_fixture[:3, :3] @ np.asarray(fixture(fixture_name).landmarks["approach"], float)


def peg_line_direction(points: np.ndarray, T_base_fixture: np.ndarray, fixture_name: str, distance: float,
                       margin: float = 0.001) -> np.ndarray:
    """Unit direction (3,), base frame, of the line onto the fixture for the held object's points
    (N, 3) at the place (base frame): the fixture's approach unless its points would hit the
    fixture on the way, then the least tilted direction that clears (the approach if none does)."""
    f = fixture(fixture_name)
    approach = np.asarray(f.landmarks["approach"], float)
    if "peg_tip" not in f.landmarks:
        return fixture_approach(T_base_fixture, fixture_name)
    local = transform_points(invert(T_base_fixture), np.asarray(points, float))  # (N, 3) fixture frame
    scene = _fixture_scene(fixture_name)
    for d in directions(approach):
        if hits(local, d, scene, distance, margin) == 0:
            return T_base_fixture[:3, :3] @ d
    return T_base_fixture[:3, :3] @ approach
