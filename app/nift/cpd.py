"""The CPD baseline (paper Table I, after Rodriguez & Behnke 2018): register demo clouds to the target
with rigid coherent point drift (Myronenko & Song 2010, the `pycpd` library) and carry the demo's
poses over with the best registration (lowest final variance sigma^2).

pycpd's convention is row vectors, y' = s y R + t; as a 4x4 on column vectors that is
[[s R^T, t], [0, 1]]. The similarity's scale moves positions only: a transferred pose keeps the
rotation R^T and has its position mapped by s R^T p + t.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pycpd import RigidRegistration

from hardware.se3 import make_pose

POINTS = 300  # both clouds are subsampled to this many points (CPD is O(M N) per iteration)


@dataclass(frozen=True)
class Registration:
    """x_target = scale * R @ x_source + t, with the final CPD variance (lower = better fit)."""

    R: np.ndarray
    t: np.ndarray
    scale: float
    sigma2: float

    def transfer(self, T_source: np.ndarray) -> np.ndarray:
        """Carry a pose from the source cloud's frame into the target's."""
        return make_pose(self.R @ T_source[:3, :3], self.scale * self.R @ T_source[:3, 3] + self.t)


def subsample(cloud: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    return cloud if len(cloud) <= n else cloud[rng.choice(len(cloud), n, replace=False)]


def register(source: np.ndarray, target: np.ndarray, seed: int = 0, max_iterations: int = 100) -> Registration:
    """Rigid CPD (with scale) of source (M, 3) onto target (N, 3)."""
    rng = np.random.default_rng(seed)
    X, Y = subsample(np.asarray(target, float), POINTS, rng), subsample(np.asarray(source, float), POINTS, rng)
    reg = RigidRegistration(X=X, Y=Y, max_iterations=max_iterations, tolerance=1e-6)
    reg.register()
    s, R, t = reg.get_registration_parameters()
    return Registration(np.asarray(R).T, np.asarray(t).reshape(3), float(s), float(reg.sigma2))


def best_registration(sources: list[np.ndarray], target: np.ndarray, seed: int = 0) -> tuple[int, Registration]:
    """The demo whose cloud registers best to the target, and that registration."""
    regs = [register(s, target, seed) for s in sources]
    k = int(np.argmin([r.sigma2 for r in regs]))
    return k, regs[k]
