"""Inverse kinematics for planning: the UR5's closed-form branches, the collision-free one nearest
the current configuration first."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.failures import NoIKSolution, PlanningFailure
from app.motion.scene import PlanningScene
from hardware.kinematics import UR5Kinematics


@dataclass(frozen=True)
class IKConfig:
    """How IK solutions are ranked: by this weighted joint distance to the current configuration."""

    joint_weights: tuple[float, ...] = (2.0, 2.0, 1.5, 1.0, 1.0, 0.5)  # move the big joints less


@dataclass(frozen=True)
class Blocked:
    """Why the cell cannot put its TCP at a pose: the quick test's answer (`reach_failure`)."""

    why: str
    gripper_hits: tuple[str, ...] = ()  # what the open gripper alone hits there (empty: it hits nothing)

    def __str__(self) -> str:
        return self.why

    @property
    def in_table(self) -> bool:
        """Whether the open gripper alone is in the table there."""
        return "table" in self.gripper_hits


def joint_distance(q: np.ndarray, q_ref: np.ndarray, weights: tuple[float, ...]) -> float:
    """Weighted Euclidean distance between configurations."""
    return float(np.linalg.norm(np.asarray(weights) * (np.asarray(q) - np.asarray(q_ref))))


def solutions(kin: UR5Kinematics, T_base_tcp: np.ndarray, q_current: np.ndarray, scene: PlanningScene | None = None,
              config: IKConfig = IKConfig(), ignore: tuple[str, ...] = (), what: str = "pose") -> list[np.ndarray]:
    """The collision-free closed-form IK branches for T_base_tcp (`UR5Kinematics.ik_all`), nearest
    q_current first; NoIKSolution (out of reach, or every branch collides - with what) if there is none."""
    found: list[np.ndarray] = []
    branches = kin.ik_all(T_base_tcp, q_current)
    blocked: set[str] = set()
    for q in branches:
        if any(np.abs(q - other).max() < 1e-3 for other in found):
            continue  # two branches meet at a singularity
        if scene is not None and (hits := scene.collisions(q, ignore)):
            blocked.update(hits)
            continue
        found.append(q)
    if not found:
        xyz = np.round(T_base_tcp[:3, 3], 3).tolist()
        if not branches:
            raise NoIKSolution(f"no IK solution for the {what} at {xyz} (out of reach)")
        raise NoIKSolution(f"every IK solution for the {what} at {xyz} collides ({', '.join(sorted(blocked)[:4])})")
    return sorted(found, key=lambda q: joint_distance(q, q_current, config.joint_weights))


def solve(kin: UR5Kinematics, T_base_tcp: np.ndarray, q_current: np.ndarray, scene: PlanningScene | None = None,
          config: IKConfig = IKConfig(), ignore: tuple[str, ...] = (), what: str = "pose") -> np.ndarray:
    """The collision-free IK solution for T_base_tcp nearest q_current; NoIKSolution says why not."""
    return solutions(kin, T_base_tcp, q_current, scene, config, ignore, what)[0]


def reach_failure(kin: UR5Kinematics, scene: PlanningScene, q_current: np.ndarray, ignore: tuple[str, ...] = ()):
    """A quick test of TCP poses, pose (4, 4) -> why the cell cannot put its TCP there (`Blocked`), or None: the
    open gripper alone hits something (`PlanningScene.gripper_collisions`), or no IK branch is
    collision-free (~2 ms a pose). A pose it passes may still fail the full plan (the lines to it)."""

    def failure(T_base_tcp: np.ndarray, what: str = "pose") -> Blocked | None:
        if hits := scene.gripper_collisions(T_base_tcp, ignore):
            return Blocked(f"the gripper at the {what} hits {', '.join(hits)}", tuple(hits))
        try:
            solutions(kin, T_base_tcp, q_current, scene, ignore=ignore, what=what)
        except PlanningFailure as exc:
            return Blocked(str(exc))
        return None

    return failure
