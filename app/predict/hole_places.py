"""Hangs built from the handle hole seen in the cloud (our addition): the hole where the demos had it.

Each demo's cloud shows its hole (`app.predict.handle_hole.find_hole`, z towards the demo's grasp)
and its place says where the fixture was relative to that cloud (`Demo.place_anchor`), so the demos
hang the hole at

    T_fixture_hole,d = inv(T_base_fixture_seen,d) @ T_base_hole,d,

averaged over the demos whose hole is found (rotations by their chordal mean, then again without
those more than OUTLIER from it). For a new cloud with
hole T_base_hole the fixture would be, relative to the object as seen,

    T_base_fixture_seen = T_base_hole @ F @ Ry(-theta) @ inv(T_fixture_hole)

with F the identity or the half-turn about the hole's radial x (the same hole, the mug facing the
other way along the peg), and Ry(theta) a turn about the hole's axis - the peg - by one of
PEG_TURNS: the mug hung as the demos hung it, or swung about the peg, which it hangs from all the
same (another way in for the gripper when the first is blocked; it swings back once let go). A grasp is paired with such a place only when carrying it there is like
the demos' carries (`app.predict.feasibility.carries_like_demos`).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial.transform import Rotation

from app.predict.pairs import Candidate
from app.predict.feasibility import carries_like_demos, demo_carries
from app.predict.handle_hole import Hole, HoleConfig, find_hole
from hardware.se3 import invert, make_pose

FLIPS = (np.eye(4), make_pose(np.diag([1.0, -1.0, -1.0]), np.zeros(3)))  # F: as found, half-turn about x
PEG_TURNS = (0.0, 0.35, -0.35, 0.7, -0.7)  # rad about the peg, in the order tried
OUTLIER = np.radians(10.0)  # a demo's hole turned this far from the others' mean is left out of it
UP = np.array([0.0, 0.0, 1.0])  # the table's normal in the base frame: a mug standing on it has this axis
HOLE_RANK = -1  # place ranks of hole places count down from this: -1, -2 (imitated places are 0, 1, ...)


def demo_hole(demos, config: HoleConfig = HoleConfig()) -> np.ndarray | None:
    """(4, 4) the demos' mean T_fixture_hole, or None when no demo's cloud shows its hole."""
    found = []
    for d in demos:
        hole = find_hole(d.cloud, d.T_base_tcp[:3, 3], config, up=UP)
        if hole is not None:
            found.append(invert(d.place_anchor()) @ hole.T)
    if not found:
        return None
    T = np.stack(found)  # (D, 4, 4)
    turns = Rotation.from_matrix(T[:, :3, :3])
    near = (turns.mean().inv() * turns).magnitude() <= OUTLIER  # (D,)
    near = near if near.any() else np.ones(len(T), bool)
    return make_pose(turns[near].mean().as_matrix(), T[near, :3, 3].mean(axis=0))


@dataclass(frozen=True)
class DemoHang:
    """What the demos say about hanging by the hole: where they hung it (`demo_hole`; None when no
    demo's cloud shows it) and how they carried their objects (`demo_carries`)."""

    T_fixture_hole: np.ndarray | None
    carried: list[np.ndarray]


def demo_hang(demos, config: HoleConfig = HoleConfig()) -> DemoHang:
    """The demos' `DemoHang`, computed once for as many clouds as need it."""
    return DemoHang(demo_hole(demos, config), demo_carries(demos))


def about_peg(theta: float) -> np.ndarray:
    """(4, 4) the turn Ry(theta) about the hole's axis y."""
    c, s = np.cos(theta), np.sin(theta)
    return make_pose(np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]), np.zeros(3))


def hole_places(hole: Hole, T_fixture_hole: np.ndarray, turns: tuple[float, ...] = PEG_TURNS) -> np.ndarray:
    """(K, 4, 4) T_base_fixture_seen that hang the seen hole as the demos did, both ways along the peg,
    turned about it by each of `turns` (K = 2 len(turns), the turns' order first)."""
    return np.stack([hole.T @ F @ about_peg(-theta) @ invert(T_fixture_hole) for theta in turns for F in FLIPS])


def hole_pairs(options: list[Candidate], places: np.ndarray, carried: list[np.ndarray]) -> list[Candidate]:
    """Each hole place (K, 4, 4) in its order, with each distinct grasp of `options` (in theirs) that
    can carry to it like the demos; the pair's place_rank is HOLE_RANK - k."""
    pairs, seen = [], set()
    for c in options:
        if c.grasp_rank in seen:
            continue
        seen.add(c.grasp_rank)
        ok = carries_like_demos(c.T_base_tcp, carried)(places)  # (K,)
        pairs += [replace(c, T_base_fixture_seen=places[k], place_rank=HOLE_RANK - int(k)) for k in np.flatnonzero(ok)]
    return sorted(pairs, key=lambda c: -c.place_rank)  # stable: the grasps' order within a place


def with_hole_pairs(options: list[Candidate], points: np.ndarray, hang: DemoHang,
                    config: HoleConfig = HoleConfig()) -> tuple[list[Candidate], dict]:
    """The hole pairs of a mug's raw points (M, 3) (z towards the best option's grasp) before `options`,
    and what was found (JSON-ready); `options` alone when the points or the demos show no hole."""
    if not options:
        return options, {"found": False, "why": "no grasp to pair"}
    if hang.T_fixture_hole is None:
        return options, {"found": False, "why": "no demo's cloud shows its hole"}
    hole = find_hole(points, options[0].T_base_tcp[:3, 3], config, up=UP)
    if hole is None:
        return options, {"found": False, "why": "the cloud shows no handle hole"}
    pairs = hole_pairs(options, hole_places(hole, hang.T_fixture_hole), hang.carried)
    return pairs + options, {"found": True, "handle_points": int(hole.handle_points), "pairs": len(pairs),
                             "center": np.round(hole.T[:3, 3], 4).tolist()}
