"""A textured plate carried on the robot flange (a calibration board) in the simulated cell.

It has no collision shape and follows `tool0` rigidly after every physics step, as a board
screwed to the flange would.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from hardware.bullet import p, pose_to_pybullet
from hardware.sim.robot import SimRobot


def _quad_obj(width: float, height: float, cells: int = 24) -> str:
    """Two-sided plate (x right, y down, z = 0) with UVs so the image reads correctly from -z.

    It is a fine grid, not two triangles: PyBullet's TinyRenderer interpolates texture
    coordinates affinely, which bends a tilted board's pattern by up to a square when the
    triangles are large.
    """
    n = cells
    lines = []
    for j in range(n + 1):
        for i in range(n + 1):
            lines.append(f"v {width * i / n:.6f} {height * j / n:.6f} 0")
            lines.append(f"vt {i / n:.6f} {1 - j / n:.6f}")
    for j in range(n):
        for i in range(n):
            a, b, c, d = (j * (n + 1) + i + 1, j * (n + 1) + i + 2, (j + 1) * (n + 1) + i + 2, (j + 1) * (n + 1) + i + 1)
            lines += [f"f {a}/{a} {b}/{b} {c}/{c}", f"f {a}/{a} {c}/{c} {d}/{d}",
                      f"f {a}/{a} {c}/{c} {b}/{b}", f"f {a}/{a} {d}/{d} {c}/{c}"]
    return "\n".join(lines) + "\n"


class FlangePlate:
    """A plate of `size` (m) showing `texture_png`, at T_tool0_plate on the robot's flange."""

    def __init__(self, robot: SimRobot, texture_png: Path, size: tuple[float, float], T_tool0_plate: np.ndarray,
                 cache: Path) -> None:
        self.robot = robot
        self.T_tool0_plate = np.asarray(T_tool0_plate, float)
        cid = robot.client
        obj = cache / f"plate_{size[0]:.4f}x{size[1]:.4f}_grid.obj"
        obj.parent.mkdir(parents=True, exist_ok=True)
        obj.write_text(_quad_obj(*size))
        vis = p.createVisualShape(p.GEOM_MESH, fileName=str(obj), physicsClientId=cid)
        self.body = p.createMultiBody(0.0, -1, vis, physicsClientId=cid)
        texture = p.loadTexture(str(texture_png), physicsClientId=cid)
        p.changeVisualShape(self.body, -1, textureUniqueId=texture, rgbaColor=[1, 1, 1, 1], physicsClientId=cid)
        robot.world.on_step.append(self.follow)
        self.follow()

    def follow(self) -> None:
        """Put the plate where the flange now is."""
        pos, quat = pose_to_pybullet(self.robot.link_pose("tool0") @ self.T_tool0_plate)
        p.resetBasePositionAndOrientation(self.body, pos, quat, physicsClientId=self.robot.client)

    def remove(self) -> None:
        """Unmount the plate."""
        self.robot.world.on_step.remove(self.follow)
        p.removeBody(self.body, physicsClientId=self.robot.client)
