"""What a job moved: the seconds the arm spent in motion verbs, on the controller's clock, and the
joints' travel (our addition, for cycle time: docs/benchmark.md).

`MeteredArm` stands in for the job's arm. Every motion verb (moveJ, moveL, executeTrajectory) is
timed by the controller's timestamp before and after it, and counted to the job's stage then
(`stage`, set by `JobContext.stage`: where the cycle goes), and its travel is the summed joint
distance actually covered,

    travel = sum_k |q_k+1 - q_k|_1        over the joint path as far as the arm got,

for a trajectory its samples up to the one nearest where the arm stopped; for moveJ and moveL the
straight joint distance from start to end (exact for moveJ; a moveL's short line is nearly straight
in joint space). Everything else passes through to the arm unchanged.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from hardware.interfaces import Arm


def path_travel(path: np.ndarray, q_end: np.ndarray) -> float:
    """Summed joint distance (rad) along the joint path (K, 6) up to its sample nearest q_end (6,) -
    the last such sample, as a path may pass through the same joints twice - then on to q_end."""
    path = np.asarray(path, float)
    d = np.abs(path - q_end).sum(axis=1)  # (K,)
    nearest = int(np.flatnonzero(d <= d.min() + 1e-9)[-1])
    return float(np.abs(np.diff(path[: nearest + 1], axis=0)).sum() + np.abs(q_end - path[nearest]).sum())


class MeteredArm:
    """The arm, counting `seconds` in motion and joint `travel` (rad) over its motion verbs."""

    def __init__(self, arm: Arm) -> None:
        self.arm = arm
        self.stage = ""  # the job's stage the next motions count to
        self.by_stage: dict[str, list[float]] = {}  # stage -> [seconds, rad]

    @property
    def seconds(self) -> float:
        """Seconds in motion so far, every stage's."""
        return sum(s for s, _ in self.by_stage.values())

    @property
    def travel(self) -> float:
        """Joint travel (rad) so far, every stage's."""
        return sum(rad for _, rad in self.by_stage.values())

    def __getattr__(self, name: str) -> Any:
        return getattr(self.arm, name)

    def moveJ(self, q: np.ndarray, speed: float = 1.05, acceleration: float = 1.4) -> bool:
        return self._metered(lambda: self.arm.moveJ(q, speed, acceleration))

    def moveL(self, pose: np.ndarray, speed: float = 0.25, acceleration: float = 1.2) -> bool:
        return self._metered(lambda: self.arm.moveL(pose, speed, acceleration))

    def executeTrajectory(self, times: np.ndarray, q: np.ndarray, qd: np.ndarray | None = None) -> bool:
        return self._metered(lambda: self.arm.executeTrajectory(times, q, qd), q)

    def record(self) -> dict:
        """JSON-ready: the seconds in motion and the joint travel so far, and each stage's (`by_stage`)."""
        return {"motion_seconds": round(self.seconds, 3), "joint_travel_rad": round(self.travel, 3),
                "by_stage": {name: {"motion_seconds": round(s, 3), "joint_travel_rad": round(rad, 3)}
                             for name, (s, rad) in self.by_stage.items()}}

    def _metered(self, move: Callable[[], bool], path: np.ndarray | None = None) -> bool:
        q0, t0 = self.arm.getActualQ(), self.arm.getTimestamp()
        try:
            return move()
        finally:
            q1 = self.arm.getActualQ()
            seconds = round(self.arm.getTimestamp() - t0, 6)  # rounded: the same motion, started later on
            # the controller's clock, differs in the last bits of the difference of two larger times
            travel = float(np.abs(q1 - q0).sum()) if path is None else path_travel(path, q1)
            counted = self.by_stage.setdefault(self.stage, [0.0, 0.0])
            counted[0] += seconds
            counted[1] += travel
