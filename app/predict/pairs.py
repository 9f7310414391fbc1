"""Grasp and place pairs a cell may execute, best first (our addition): a cell keeps several good
answers and carries out the first one it can reach (`app.jobs.choice`).

Imitation gives distinct grasp candidates G_k and place candidates P_j (`app.nift.candidates`), each
with its Eq. 5 loss. A pair is scored by how far both lie above their stage's best, relative,

    s(k, j) = (L_G,k - L_G,0) / |L_G,0| + (L_P,j - L_P,0) / |L_P,0|

and kept only when the grasp carried to the place is consistent with the demos
(`app.predict.feasibility.carries_like_demos`): a place that turns the object over relative to
that grasp is no option for it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.nift.imitate import Imitation
from app.predict.feasibility import carries_like_demos
from hardware.se3 import invert

MOST_PAIRS = 16


@dataclass(frozen=True)
class Candidate:
    """One grasp and place pair: the grasp in the base frame, where the fixture would be relative to
    the object as seen, and the real fixture's pose; `score` 0 is the best of both stages."""

    T_base_tcp: np.ndarray
    T_base_fixture_seen: np.ndarray
    T_base_fixture: np.ndarray
    score: float = 0.0
    grasp_rank: int = 0
    place_rank: int = 0

    @property
    def motion(self) -> np.ndarray:
        """The rigid motion taking the object from where it is to its place on the real fixture."""
        return self.T_base_fixture @ invert(self.T_base_fixture_seen)

    @property
    def T_base_tcp_place(self) -> np.ndarray:
        """The gripper's pose at the place with this grasp held rigidly."""
        return self.motion @ self.T_base_tcp


def excess(losses: np.ndarray) -> np.ndarray:
    """(K,) each loss's relative excess over the first (the best)."""
    losses = np.asarray(losses, float)
    return (losses - losses[0]) / max(abs(losses[0]), 1e-12)


def ranked_pairs(grasp: Imitation, place: Imitation, T_base_fixture: np.ndarray,
                 carried: list[np.ndarray] | None = None, most: int = MOST_PAIRS) -> list[Candidate]:
    """The candidate pairs, best score first, at most `most`; with the demos' T_fixture_tcp
    (`carried`) only the pairs whose grasp carried to the place is consistent with them."""
    G, P = grasp.candidates, place.candidates  # (K, 4, 4), (J, 4, 4)
    sg, sp = excess(grasp.candidate_losses), excess(place.candidate_losses)  # (K,), (J,)
    pairs = []
    for k in range(len(G)):
        ok = carries_like_demos(G[k], carried)(P) if carried else np.ones(len(P), bool)  # (J,)
        pairs += [Candidate(G[k], P[j], T_base_fixture, float(sg[k] + sp[j]), k, int(j)) for j in np.flatnonzero(ok)]
    pairs.sort(key=lambda c: c.score)
    return pairs[:most]
