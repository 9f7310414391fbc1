"""The cell's layout: where the rack and the shelf stand on the table, in the robot's base frame.

Base frame (metres): the robot base at the origin on the table top (z = 0); the rack stands to
the robot's left with the peg pointing back at it and up at 45 degrees; the shelf to its right.
The job path (planning scene, predictions) takes fixture poses from here, never from the
simulator; the simulated cell's `CellConfig` extends it with the simulated devices' settings.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hardware.se3 import make_pose, rotvec_to_matrix


@dataclass(frozen=True)
class CellLayout:
    """Where the fixtures stand: (x, y, yaw) on the table of each."""

    rack_xy_yaw: tuple[float, float, float] = (0.55, 0.40, np.pi)  # peg points back towards the robot
    shelf_xy_yaw: tuple[float, float, float] = (0.50, -0.45, 0.0)

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
