"""What a generated instance knows about itself: its shape parameters and semantic landmarks.

The scripted teacher (demos), the success judges and the tests read these; the method never does.
All lengths in metres, in the instance's canonical frame (upright, +z up, resting on z = 0, axis
of revolution on the z axis, the handle - if any - towards +x).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np


@dataclass(frozen=True)
class Semantics:
    """Semantic landmarks of one procedural instance (canonical frame, metres)."""

    category: str
    seed: int
    params: dict[str, float] = field(repr=False)  # the sampled shape parameters, see RANGES
    height: float
    max_radius: float
    rim_height: float  # z of the rim / opening (for a bottle: the top of the neck)
    rim_radius: float  # outer radius at the rim
    rim_inner_radius: float | None = None  # inner radius at the rim (None: closed top)
    handle_center: tuple[float, float, float] | None = None  # centre of the handle's hole
    handle_axis: tuple[float, float, float] | None = None  # a peg through the hole runs along it
    neck_height: float | None = None  # z of the middle of a bottle's straight neck
    neck_radius: float | None = None
    neck_range: tuple[float, float] | None = None  # (z bottom, z top) of the straight neck

    def to_dict(self) -> dict:
        """Plain-JSON form."""
        return asdict(self)


def sample_params(ranges: dict[str, tuple[float, float]], rng: np.random.Generator) -> dict[str, float]:
    """Draw each parameter uniformly from its (low, high) range, in the dict's order."""
    return {name: float(rng.uniform(lo, hi)) for name, (lo, hi) in ranges.items()}
