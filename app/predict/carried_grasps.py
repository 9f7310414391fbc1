"""Grasps carried over from the place (our addition, for the cell): the demos' grasp, put where the
place's imitation says the fixture is.

Grasp and place are imitated separately (paper Sec. III-C). On one Kinect view a mug's rim looks the
same all round, so the grasp imitation picks a rim point at any azimuth, while in every demo the
gripper held the rim at one side of the handle: hung on the peg with the grasp found, the gripper
then sat 6-10 cm from where any demo's was, inside the rack's post (docs/decisions.md). The place's
imitation, which does use the handle,
says where the fixture would be relative to the object, T_base_fixture_seen; each demo d held the
object with the TCP at C_d = inv(T_base_fixture_d) @ T_base_tcp_d relative to its fixture. So

    G_jd = T_base_fixture_seen,j @ C_d

is a grasp that carries to place candidate j exactly as demo d carried its object. These grasps,
one per distinct pose, that close on something (and pass the caller's predicate), join the pairs
with the place they came from, scored by their own Eq. 5 grasp loss like any other pair.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from app.nift.candidates import IDENTITY, CandidateConfig, leaders
from app.nift.imitate import Imitation
from app.predict.pairs import Candidate, excess
from app.predict.feasibility import Predicate

Losses = Callable[[np.ndarray], np.ndarray]  # grasp poses (K, 4, 4) -> (K,) their Eq. 5 losses


def carried_grasps(places: np.ndarray, carried: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(J * D, 4, 4) grasps G_jd = places[j] @ carried[d], and (J * D,) the place index j of each."""
    C = np.asarray(carried, float)  # (D, 4, 4)
    G = np.einsum("jab,dbc->jdac", places, C).reshape(-1, 4, 4)
    return G, np.repeat(np.arange(len(places)), len(C))


def medoid(carried: list[np.ndarray]) -> np.ndarray:
    """(4, 4) the demo relation C_d whose TCP position lies nearest the others' (summed distance)."""
    t = np.asarray(carried, float)[:, :3, 3]  # (D, 3)
    return np.asarray(carried[int(np.linalg.norm(t[:, None] - t[None], axis=-1).sum(axis=1).argmin())], float)


def carried_places(grasps: np.ndarray, carried: list[np.ndarray]) -> np.ndarray:
    """(K, 4, 4) fixture poses P_k = G_k @ inv(C) relative to the object, C the medoid demo: where the
    fixture would be had the demo's carry held with grasp G_k - starts for the place's imitation."""
    return np.asarray(grasps, float) @ np.linalg.inv(medoid(carried))


def carried_pairs(grasp: Imitation, place: Imitation, T_base_fixture: np.ndarray, carried: list[np.ndarray],
                  losses: Losses, feasible: Predicate | None = None,
                  symmetries: tuple[np.ndarray, ...] = IDENTITY, config: CandidateConfig = CandidateConfig(),
                  first_rank: int = 0) -> list[Candidate]:
    """Pairs (place candidate j, a grasp carried from it), one per distinct grasp, feasible ones only;
    score = the grasp loss's excess over the grasp imitation's best + the place's excess;
    grasp ranks from `first_rank` on (after the imitation's own)."""
    places = place.candidates  # (J, 4, 4)
    G, j_of = carried_grasps(places, carried)  # (J D, 4, 4), (J D,)
    if feasible is not None:
        ok = feasible(G)
        G, j_of = G[ok], j_of[ok]
    if len(G) == 0:
        return []
    L = np.asarray(losses(G), float)  # (K,)
    lead, _ = leaders(G, L, config, symmetries)
    best_grasp = float(grasp.candidate_losses[0])
    sp = excess(place.candidate_losses)  # (J,)
    return [Candidate(G[k], places[j_of[k]], T_base_fixture,
                      float((L[k] - best_grasp) / max(abs(best_grasp), 1e-12) + sp[j_of[k]]), first_rank + i,
                      int(j_of[k]))
            for i, k in enumerate(lead[: config.most])]
