"""Fixtures of the cell: the mug rack (a post with one peg at 45 degrees, like NDF's) and the shelf.

Each fixture is a watertight mesh in its own frame (base on z = 0) with named landmarks, so the
scripted teacher and the success judges can say where the peg or the shelf top is.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh
from manifold3d import Manifold

from app.objects.solids import to_trimesh

# Rack (metres, degrees)
RACK_BASE = (0.14, 0.14, 0.012)  # base plate x, y, z size
RACK_POST_RADIUS = 0.012
RACK_POST_HEIGHT = 0.32
RACK_PEG_RADIUS = 0.006
RACK_PEG_LENGTH = 0.10
RACK_PEG_HEIGHT = 0.24  # where the peg leaves the post's axis
RACK_PEG_ELEVATION_DEG = 45.0  # peg rises at this angle from horizontal, towards +x

# Shelf: a board on two legs
SHELF_SIZE = (0.30, 0.30)  # board x, y
SHELF_THICKNESS = 0.02
SHELF_TOP = 0.14  # z of the board's top surface
SHELF_LEG_WIDTH = 0.03


@dataclass(frozen=True)
class Fixture:
    """A static fixture: its mesh (fixture frame) and landmarks (fixture frame, metres); the
    `approach` landmark is the unit direction an object comes from when it is put on it."""

    name: str
    mesh: trimesh.Trimesh = field(repr=False)
    landmarks: dict[str, tuple[float, ...] | float]


def _box(size: tuple[float, float, float], centre: tuple[float, float, float]) -> Manifold:
    return Manifold.cube(size, center=True).translate(centre)


def rack() -> Fixture:
    """The mug rack: base plate, vertical post on the z axis, one peg rising at 45 degrees towards +x."""
    base = _box(RACK_BASE, (0.0, 0.0, RACK_BASE[2] / 2))
    post = Manifold.cylinder(RACK_POST_HEIGHT, RACK_POST_RADIUS, circular_segments=32)
    elev = np.radians(RACK_PEG_ELEVATION_DEG)
    direction = np.array([np.cos(elev), 0.0, np.sin(elev)])
    # A z-cylinder tilted about +y by (90 - elevation) degrees points along `direction`.
    peg = (Manifold.cylinder(RACK_PEG_LENGTH, RACK_PEG_RADIUS, circular_segments=24)
           .rotate((0.0, 90.0 - RACK_PEG_ELEVATION_DEG, 0.0))
           .translate((0.0, 0.0, RACK_PEG_HEIGHT)))
    origin = np.array([0.0, 0.0, RACK_PEG_HEIGHT])
    tip = origin + RACK_PEG_LENGTH * direction
    return Fixture("rack", to_trimesh(base + post + peg), {
        "peg_origin": tuple(map(float, origin)), "peg_tip": tuple(map(float, tip)),
        "peg_direction": tuple(map(float, direction)),
        "peg_radius": RACK_PEG_RADIUS, "peg_length": RACK_PEG_LENGTH,
        "approach": tuple(map(float, direction)),  # a mug comes onto the peg from its tip
    })


def shelf() -> Fixture:
    """The shelf: a board whose top is at SHELF_TOP, on two legs along the y edges."""
    sx, sy = SHELF_SIZE
    board = _box((sx, sy, SHELF_THICKNESS), (0.0, 0.0, SHELF_TOP - SHELF_THICKNESS / 2))
    leg_h = SHELF_TOP - SHELF_THICKNESS
    legs = [_box((sx, SHELF_LEG_WIDTH, leg_h), (0.0, s * (sy - SHELF_LEG_WIDTH) / 2, leg_h / 2)) for s in (-1, 1)]
    return Fixture("shelf", to_trimesh(board + legs[0] + legs[1]), {
        "top_center": (0.0, 0.0, SHELF_TOP), "top_size": (sx, sy),
        "approach": (0.0, 0.0, 1.0),  # objects come down onto the board
    })


FIXTURES = {"rack": rack, "shelf": shelf}


def fixture(name: str) -> Fixture:
    """A fixture by name ('rack' or 'shelf')."""
    if name not in FIXTURES:
        raise ValueError(f"unknown fixture {name!r}; choose one of {', '.join(FIXTURES)}")
    return FIXTURES[name]()
