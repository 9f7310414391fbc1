"""The carry's path constraint: a held object is not to pivot in the fingers (`Planner.carry`)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from hardware.kinematics import UR5Kinematics


def held_without_pivot(kin: UR5Kinematics, q0: np.ndarray, q1: np.ndarray, extra: float) -> Callable[[np.ndarray], bool]:
    """The carry's path constraint. A two-finger grip resists turns about every axis but the fingers'
    own (the tool's y), where only the pads' torsional friction holds the object, so gravity may swing
    about that axis, seen from the tool, at most as far as `extra` degrees (or as far as q1 needs); an
    object turned on its head over the fingers (swing 2) is refused too, balanced as it may be:

        g(q) = R(q)^T (0, 0, -1)                   gravity in the tool frame
        p(q) = g(q) - (g(q) . y) y                 its part across the fingers' axis
        swing(q) = | p(q) - |p(q)| p(q0) / |p(q0)| |   = |p(q)| 2 sin(theta / 2), theta its turn about y
        swing(q) <= max(swing(q1), 2 sin(extra / 2))
    """
    down, y = np.array([0.0, 0.0, -1.0]), np.array([0.0, 1.0, 0.0])

    def across(q: np.ndarray) -> np.ndarray:
        g = kin.fk(q)[:3, :3].T @ down  # (3,)
        return g - (g @ y) * y

    p0 = across(q0)
    if np.linalg.norm(p0) < 1e-3:  # the fingers' axis vertical: gravity cannot pivot the object
        return lambda q: True
    p0 = p0 / np.linalg.norm(p0)

    def swing(q: np.ndarray) -> float:
        p = across(q)
        return float(np.linalg.norm(p - np.linalg.norm(p) * p0))

    limit = max(swing(q1), 2.0 * np.sin(np.radians(extra) / 2.0)) + 1e-9
    return lambda q: bool(swing(q) <= limit)
