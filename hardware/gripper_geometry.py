"""Our two-finger parallel gripper: geometry (documented here) and its URDF, attached at tool0.

Dimensions (metres), in the tool0 frame (z out of the flange, fingers move along y):

| part    | size (x, y, z)          | where                                                 |
|---------|-------------------------|-------------------------------------------------------|
| palm    | 0.050 x 0.150 x 0.060   | z from 0 to 0.060                                     |
| finger  | 0.022 x 0.012 x 0.060   | z from 0.060 to 0.120; inner faces at y = +-width / 2 |
| pad     | friction 1.5 on the inner face of each finger                                    |

Stroke 0 to 0.085 m (each finger travels 0.0425 m), prismatic joints with a 60 N force limit.
The TCP - the point between the pad centres - is 0.100 m along tool0's z.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class GripperGeometry:
    """Sizes of the gripper (metres, kilograms, newtons)."""

    palm: tuple[float, float, float] = (0.050, 0.150, 0.060)
    finger: tuple[float, float, float] = (0.022, 0.012, 0.060)
    stroke: float = 0.085
    max_force: float = 60.0
    max_speed: float = 0.15  # m/s of the opening
    palm_mass: float = 0.6
    finger_mass: float = 0.05
    pad_friction: float = 1.5

    @property
    def tcp_z(self) -> float:
        """Distance from tool0 to the TCP between the pad centres."""
        return self.palm[2] + self.finger[2] * 2.0 / 3.0

    @property
    def T_tool0_tcp(self) -> np.ndarray:
        """4x4 TCP offset from tool0."""
        T = np.eye(4)
        T[2, 3] = self.tcp_z
        return T


    def corners(self, width: float | None = None) -> np.ndarray:
        """(24, 3) corners of the palm's and the two fingers' boxes in the TCP frame, the fingers
        `width` apart (default fully open)."""
        w = self.stroke if width is None else width
        (px, py, pz), (fx, fy, fz) = self.palm, self.finger
        boxes = [((-px / 2, px / 2), (-py / 2, py / 2), (0.0, pz))]
        boxes += [((-fx / 2, fx / 2), tuple(sorted((s * w / 2, s * (w / 2 + fy)))), (pz, pz + fz)) for s in (1, -1)]
        out = [[x, y, z - self.tcp_z] for xs, ys, zs in boxes for x in xs for y in ys for z in zs]
        return np.array(out)


    def contains(self, points_tcp: np.ndarray, width: float | None = None, margin: float = 0.0,
                 sweep: float = 0.0) -> np.ndarray:
        """(N,) bool: which points (N, 3), in the TCP frame, lie inside the palm's or a finger's box
        (`corners`, fingers `width` apart) grown by `margin` on every side, or inside the volume each
        box sweeps coming in along the tool axis from `sweep` metres back (z - sweep to z)."""
        boxes = self.corners(width).reshape(3, 8, 3)  # palm, finger, finger
        lo, hi = boxes.min(axis=1) - margin, boxes.max(axis=1) + margin  # (3, 3)
        lo[:, 2] -= sweep
        p = np.asarray(points_tcp, float)[:, None]  # (N, 1, 3)
        return ((p >= lo) & (p <= hi)).all(axis=-1).any(axis=-1)


def lowest_point(T_base_tcp: np.ndarray, geometry: GripperGeometry = GripperGeometry()) -> float:
    """Height (m, base frame) of the open gripper's lowest corner at a TCP pose: below the table top
    (z = 0) the gripper would be in the table."""
    return float((geometry.corners() @ T_base_tcp[:3, :3].T + T_base_tcp[:3, 3])[:, 2].min())


FINGER_JOINTS = ("finger_left_joint", "finger_right_joint")
FINGER_LINKS = ("finger_left", "finger_right")
PALM_LINK = "gripper_palm"


def _box_link(name: str, size, xyz, mass: float, rgba: str) -> str:
    sx, sy, sz = size
    x, y, z = xyz
    geom = f'<geometry><box size="{sx} {sy} {sz}"/></geometry>'
    ixx = mass / 12 * (sy * sy + sz * sz)
    iyy = mass / 12 * (sx * sx + sz * sz)
    izz = mass / 12 * (sx * sx + sy * sy)
    return f"""
  <link name="{name}">
    <inertial><origin xyz="{x} {y} {z}"/><mass value="{mass}"/>
      <inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><origin xyz="{x} {y} {z}"/>{geom}<material name="{name}_mat"><color rgba="{rgba}"/></material></visual>
    <collision><origin xyz="{x} {y} {z}"/>{geom}</collision>
  </link>"""


def gripper_urdf_fragment(g: GripperGeometry = GripperGeometry(), parent: str = "tool0") -> str:
    """URDF links and joints of the gripper, fixed to `parent` (insert before </robot>)."""
    px, py, pz = g.palm
    fx, fy, fz = g.finger
    half = g.stroke / 2
    parts = [_box_link(PALM_LINK, g.palm, (0, 0, pz / 2), g.palm_mass, "0.25 0.25 0.28 1")]
    parts.append(f"""
  <joint name="gripper_mount" type="fixed">
    <parent link="{parent}"/><child link="{PALM_LINK}"/><origin xyz="0 0 0" rpy="0 0 0"/>
  </joint>""")
    for name, joint, sign in zip(FINGER_LINKS, FINGER_JOINTS, (1, -1)):
        # joint value s = how far the finger has opened; inner face at y = sign * s
        parts.append(_box_link(name, g.finger, (0, sign * fy / 2, fz / 2), g.finger_mass, "0.1 0.1 0.1 1"))
        parts.append(f"""
  <joint name="{joint}" type="prismatic">
    <parent link="{PALM_LINK}"/><child link="{name}"/>
    <origin xyz="0 0 {pz}"/><axis xyz="0 {sign} 0"/>
    <limit lower="0" upper="{half}" effort="{g.max_force}" velocity="{g.max_speed / 2}"/>
  </joint>""")
    return "".join(parts)


def standalone_gripper_urdf(g: GripperGeometry = GripperGeometry()) -> str:
    """A free-floating gripper (root link `tool0`), used by the grasp judge."""
    return f"""<?xml version="1.0"?>
<robot name="nift_gripper">
  <link name="tool0">
    <inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>{gripper_urdf_fragment(g)}
</robot>
"""
