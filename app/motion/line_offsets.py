"""Where a straight line of a pick and place may end: the default, then the alternatives that keep the task."""
from __future__ import annotations

import numpy as np

from app.motion.config import MotionConfig


def line_offsets(axis: np.ndarray, distance: float, config: MotionConfig) -> list[np.ndarray]:
    """Where a straight line may end (3,), relative to where it starts, `distance` along the unit `axis`
    first, then the alternatives that keep the task: the same axis at `shorter` fractions of the
    distance, and directions `approach_cone` off the axis at 6 azimuths."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    offsets = [axis * distance * k for k in (1.0, *config.shorter)]
    tilt = np.radians(config.approach_cone)
    e1 = np.cross(axis, [0.0, -1.0, 0.0] if abs(axis[1]) < 0.9 else [-1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)  # (e1, e2) span the plane across the axis (e1 = -x for the tool's -z)
    for azimuth in np.arange(6 if tilt > 0 else 0) * np.pi / 3:
        across = np.cos(azimuth) * e1 - np.sin(azimuth) * e2
        offsets.append(distance * (np.cos(tilt) * axis + np.sin(tilt) * across))
    return offsets


def approach_offsets(config: MotionConfig) -> list[np.ndarray]:
    """Pre-grasp positions (3,) in the grasp's TCP frame: `approach_distance` back along the tool axis,
    then the alternatives (`line_offsets`); the grasp pose itself is unchanged."""
    return line_offsets(np.array([0.0, 0.0, -1.0]), config.approach_distance, config)
