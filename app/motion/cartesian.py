"""Straight-line TCP motions (approach, lift, retreat): dense IK along the line with a continuity check."""
from __future__ import annotations

import numpy as np

from app.motion.ik import NoIKSolution
from app.motion.scene import PlanningScene
from app.se3 import interpolate_pose, line_length
from hardware.kinematics import UR5Kinematics

STEP = 0.004  # m (or 0.04 rad / 10) between IK points along the line
MAX_JOINT_JUMP = 0.08  # rad between neighbouring IK points; more means a branch switch


def line_path(kin: UR5Kinematics, T0: np.ndarray, T1: np.ndarray, q0: np.ndarray, scene: PlanningScene | None = None,
              ignore: tuple[str, ...] = (), what: str = "line") -> np.ndarray:
    """Joint positions (K, 6) tracing the TCP from T0 (at q0) to T1 on a straight line, each seeded
    by the previous; NoIKSolution if IK fails, jumps or collides on the way."""
    n = max(2, int(np.ceil(line_length(T0, T1) / STEP)) + 1)
    path = [np.asarray(q0, float)]
    for i in range(1, n):
        s = i / (n - 1)
        q = kin.ik(interpolate_pose(T0, T1, s), path[-1])
        if q is None:
            raise NoIKSolution(f"{what}: no IK solution at {100 * s:.0f}% of the straight line")
        if np.abs(q - path[-1]).max() > MAX_JOINT_JUMP:
            raise NoIKSolution(f"{what}: the arm would have to flip its configuration at {100 * s:.0f}% of the line")
        if scene is not None and (hits := scene.collisions(q, ignore)):
            raise NoIKSolution(f"{what}: collision at {100 * s:.0f}% of the line ({', '.join(hits[:3])})")
        path.append(q)
    return np.array(path)
