"""Distinct candidates among an imitation's poses (our addition): a cell keeps several good answers
and executes one it can reach, so imitation hands on a ranked set rather than its single best pose.

Two anchor poses T_a, T_b are the same candidate when their anchors lie within `translation` of
each other and the rotation between them, up to the anchor's symmetries S (a two-finger grasp
turned half a turn about its approach axis is the same grasp), is below `rotation`:

    same(T_a, T_b)  <=>  |t_a - t_b| < translation  and  min_{S}  angle(R_a^T R_b S) < rotation

`leaders` orders poses by loss and keeps the first of each group of same poses ("greedy
clustering"): the pruning of `app.nift.imitate` drops followers before leaders, so exploration
keeps one representative of every basin instead of several copies of the deepest one, and
`candidates` returns the leaders whose loss lies within a relative `margin` of the best,

    L_k <= L_best (1 + margin).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hardware.settings import check_integers, check_ranges
from hardware.se3 import make_pose, rotvec_to_matrix

HALF_TURN_Z = make_pose(rotvec_to_matrix([0.0, 0.0, np.pi]))  # a two-finger grasp's symmetry
IDENTITY = (np.eye(4),)


@dataclass(frozen=True)
class CandidateConfig:
    """When two poses are one candidate, and how far above the best a candidate's loss may lie."""

    margin: float = 0.15  # relative: candidates have L <= L_best (1 + margin)
    translation: float = 0.015  # m between anchors
    rotation: float = float(np.radians(20.0))  # rad between orientations, up to the symmetries
    most: int = 8  # at most this many candidates

    def __post_init__(self) -> None:
        check_integers(self, ("most",))
        check_ranges(self, (("margin", 0.0, 100.0, "(relative)", True), ("translation", 0.0, 1.0, "m", True),
                            ("rotation", 0.0, float(np.pi), "rad", True), ("most", 1, 1000, "", True)))


def same_pose(poses: np.ndarray, T: np.ndarray, config: CandidateConfig,
              symmetries: tuple[np.ndarray, ...] = IDENTITY) -> np.ndarray:
    """(K,) bool: which of poses (K, 4, 4) are the same candidate as T (4, 4); the angle test is
    angle(R) < a  <=>  (trace R - 1) / 2 > cos a, batched (no rotation vectors)."""
    near = np.linalg.norm(poses[:, :3, 3] - T[:3, 3], axis=-1) < config.translation  # (K,)
    S = np.stack([s[:3, :3] for s in symmetries])  # (S, 3, 3)
    cosines = (np.einsum("ba,kbc,sca->sk", T[:3, :3], poses[:, :3, :3], S) - 1.0) / 2.0  # (S, K) cos angle
    return near & (cosines.max(axis=0) > np.cos(config.rotation))


def leaders(poses: np.ndarray, losses: np.ndarray, config: CandidateConfig = CandidateConfig(),
            symmetries: tuple[np.ndarray, ...] = IDENTITY) -> tuple[np.ndarray, np.ndarray]:
    """(leaders, followers): indices into poses (K, 4, 4) ordered by loss (K,); a leader is the
    lowest-loss pose of its group, a follower is the same candidate as some leader of lower loss."""
    order = np.argsort(losses, kind="stable")
    lead: list[int] = []
    follow: list[int] = []
    for k in order:
        if lead and same_pose(poses[lead], poses[k], config, symmetries).any():
            follow.append(int(k))
        else:
            lead.append(int(k))
    return np.array(lead, dtype=int), np.array(follow, dtype=int)


def candidates(poses: np.ndarray, losses: np.ndarray, config: CandidateConfig = CandidateConfig(),
               symmetries: tuple[np.ndarray, ...] = IDENTITY, allowed: np.ndarray | None = None) -> np.ndarray:
    """Indices of the distinct candidates, best first: leaders with L <= L_best (1 + margin), at most
    `config.most`; `allowed` (K,) bool restricts them (e.g. to feasible poses) when any is allowed."""
    losses = np.asarray(losses, float)
    pool = np.flatnonzero(allowed) if allowed is not None and np.any(allowed) else np.arange(len(losses))
    pool = pool[np.isfinite(losses[pool])]
    if len(pool) == 0:
        return np.zeros(0, dtype=int)
    lead, _ = leaders(poses[pool], losses[pool], config, symmetries)
    ranked = pool[lead]
    best = losses[ranked[0]]
    within = losses[ranked] <= best + abs(best) * config.margin
    return ranked[within][: config.most]
