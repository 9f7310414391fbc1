"""Straight-line TCP motions (approach, lift, retreat): dense IK along the line with a continuity check.

A step whose joints move more than MAX_JOINT_JUMP is either fast but continuous motion (near the
wrist singularity, q5 ~ 0: a mug hung on the rack's peg is released there) or a branch switch (a
configuration flip). The step is bisected, each half seeded by the one before, down to 1/2^REFINE
of it: continuous motion then moves every sub-step less than MAX_JOINT_JUMP, a flip keeps its jump.
Continuous steps are kept (the timing then slows the line so no joint exceeds its limits).
"""
from __future__ import annotations

import numpy as np

from app.failures import NoIKSolution, PathCollides
from app.motion.scene import PlanningScene
from hardware.kinematics import UR5Kinematics
from hardware.se3 import interpolate_pose, line_length

STEP = 0.004  # m (or 0.04 rad / 10) between IK points along the line
MAX_JOINT_JUMP = 0.08  # rad between neighbouring IK points; more, at every subdivision, means a branch switch
REFINE = 4  # bisections of a step before a jump counts as a branch switch (0.25 mm sub-steps)


def continued_ik(kin: UR5Kinematics, T0: np.ndarray, T1: np.ndarray, s0: float, s1: float, q0: np.ndarray,
                 depth: int = REFINE) -> np.ndarray | None:
    """IK at interpolate_pose(T0, T1, s1) reached continuously from q0 (the solution at s0): bisect
    the step while its joints jump; None when IK fails or a jump persists at the finest step."""
    q1 = kin.ik_nearest(interpolate_pose(T0, T1, s1), q0)
    if q1 is None or np.abs(q1 - q0).max() <= MAX_JOINT_JUMP:
        return q1
    if depth == 0:
        return None
    mid = 0.5 * (s0 + s1)
    q_mid = continued_ik(kin, T0, T1, s0, mid, q0, depth - 1)
    return None if q_mid is None else continued_ik(kin, T0, T1, mid, s1, q_mid, depth - 1)


def line_path(kin: UR5Kinematics, T0: np.ndarray, T1: np.ndarray, q0: np.ndarray, scene: PlanningScene | None = None,
              ignore: tuple[str, ...] = (), what: str = "line") -> np.ndarray:
    """Joint positions (K, 6) tracing the TCP from T0 (at q0) to T1 on a straight line, each the
    closed-form branch nearest the previous; NoIKSolution if IK fails or flips on the way, PathCollides
    where it collides."""
    n = max(2, int(np.ceil(line_length(T0, T1) / STEP)) + 1)
    path = [np.asarray(q0, float)]
    for i in range(1, n):
        s = i / (n - 1)
        q = kin.ik_nearest(interpolate_pose(T0, T1, s), path[-1])
        if q is None:
            raise NoIKSolution(f"{what}: no IK solution at {100 * s:.0f}% of the straight line")
        if np.abs(q - path[-1]).max() > MAX_JOINT_JUMP:  # fast, or a flip: look closer
            q = continued_ik(kin, T0, T1, (i - 1) / (n - 1), s, path[-1])
        if q is None:
            raise NoIKSolution(f"{what}: the arm would have to flip its configuration at {100 * s:.0f}% of the line")
        if scene is not None and (hits := scene.collisions(q, ignore)):
            raise PathCollides(f"{what}: collision at {100 * s:.0f}% of the line ({', '.join(hits[:3])})")
        path.append(q)
    return np.array(path)
