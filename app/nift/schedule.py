"""The cosine step-size schedule shared by training and the pose optimiser."""

import numpy as np


def cosine(start: float, end: float, progress: float) -> float:
    """Step size at `progress` in [0, 1] (clipped): end + (start - end) * (1 + cos(pi * progress)) / 2."""
    progress = min(max(progress, 0.0), 1.0)
    return end + 0.5 * (start - end) * (1 + np.cos(np.pi * progress))
