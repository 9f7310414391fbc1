"""The cell's layout: where the rack and the shelf stand on the table, in the robot's base frame.

Base frame (metres): the robot base at the origin on the table top (z = 0); the rack stands to
the robot's left with the peg pointing back at it and up at 45 degrees; the shelf to its right.
The job path (planning scene, predictions) takes fixture poses from here, never from the
simulator; the simulated cell's `CellConfig` extends it with the simulated devices' settings.
"""
from __future__ import annotations

from dataclasses import dataclass

import math

import numpy as np

from hardware.se3 import make_pose, rotvec_to_matrix

FIXTURE_REACH = 1.2  # m from the base: no fixture farther (a UR5 reaches 0.85 m)


def checked_vector(name: str, value: tuple, length: int, norm_limit: float, what: str = "m") -> None:
    """A one-line ValueError unless `value` holds `length` finite numbers whose first three (or all, when
    fewer) lie within `norm_limit` of the origin."""
    if len(value) != length or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise ValueError(f"{name} must be {length} numbers, got {list(value)!r}")
    if not all(math.isfinite(v) for v in value):
        raise ValueError(f"{name} must be finite, got {list(value)!r}")
    if (norm := math.hypot(*value[:3])) > norm_limit:
        raise ValueError(f"{name} {list(value)!r} is {norm:.3g} {what} from the robot base; at most {norm_limit} {what}")


@dataclass(frozen=True)
class CellLayout:
    """Where the fixtures stand: (x, y, yaw) on the table of each."""

    rack_xy_yaw: tuple[float, float, float] = (0.55, 0.40, np.pi)  # peg points back towards the robot
    shelf_xy_yaw: tuple[float, float, float] = (0.50, -0.45, 0.0)

    def __post_init__(self) -> None:
        for name in ("rack_xy_yaw", "shelf_xy_yaw"):
            value = getattr(self, name)
            checked_vector(name, value, 3, math.inf)
            checked_vector(f"{name}'s x, y", value[:2], 2, FIXTURE_REACH)

    def fixture_pose(self, name: str) -> np.ndarray:
        """T_base_fixture of 'rack' or 'shelf'."""
        x, y, yaw = self.rack_xy_yaw if name == "rack" else self.shelf_xy_yaw
        return make_pose(rotvec_to_matrix([0.0, 0.0, yaw]), [x, y, 0.0])


FIXTURES = ("rack", "shelf")


def fixture_meshes(layout: CellLayout) -> list:
    """Every fixture's mesh (trimesh) in the base frame, where the layout stands it."""
    from app.objects import fixture

    return [fixture(name).mesh.copy().apply_transform(layout.fixture_pose(name)) for name in FIXTURES]


def add_fixtures(client: int, layout: CellLayout, margin: float | None = None) -> dict[str, int]:
    """Build the rack and the shelf in a PyBullet client at their configured poses, their hulls grown
    by `margin` (m; None: Bullet's default); {name: body}."""
    from app.objects import fixture
    from app.objects.collision import collision_model, visual_model
    from hardware.bullet import add_mesh

    bodies = {}
    for name in FIXTURES:
        mesh = fixture(name).mesh
        bodies[name] = add_mesh(client, visual_model(mesh), collision_model(mesh), layout.fixture_pose(name),
                                rgba=(0.55, 0.4, 0.3, 1), margin=margin)
    return bodies
