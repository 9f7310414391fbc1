"""What a job reports and how its stages fail: the record, the cell's hooks, the stage timer."""
from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from app.failures import GraspSlipped
from hardware.interfaces import Gripper
from hardware.se3 import pose_to_ur

STAGES = ("capture", "perceive", "imitate", "plan", "approach", "grasp", "lift", "recover", "look", "carry", "place",
          "release", "retreat", "verify")


class JobHooks:
    """Cell-specific steps of a job; this default does nothing and cannot verify the outcome."""

    def on_grasped(self) -> None:
        """The fingers have closed on the object."""

    def keyframe(self, label: str) -> None:
        """A stage has finished (take a picture, log, ...)."""

    def verify(self, seen: tuple[bool, str]) -> tuple[bool, str]:
        """(success, why) once the object has been let go on the fixture; `seen` is the job's own
        camera check (`app.jobs.check.Sighting.placed` and `why`), which this default reports."""
        return seen


def check_held(gripper: Gripper, during: str) -> None:
    """GraspSlipped when the gripper no longer holds the object after the motion `during`."""
    if not gripper.object_detected:
        raise GraspSlipped(f"object dropped during the {during} (gripper width {1000 * gripper.width:.1f} mm)")


@dataclass
class JobResult:
    """What happened: success, the failing stage and why, timings, poses, the plan's figures, and
    every candidate pair looked at and every grasp attempted."""

    task: str
    method: str
    success: bool = False
    failed_stage: str | None = None
    failure_kind: str | None = None  # `app.failures`: the failure's kind, or "internal_error" for a bug
    reason: str = ""
    seconds: dict[str, float] = field(default_factory=dict)  # wall time per stage, summed over attempts
    poses: dict[str, list[float]] = field(default_factory=dict)  # UR poses [x y z rx ry rz], base frame
    plan: dict[str, float] = field(default_factory=dict)
    motion: dict[str, float] = field(default_factory=dict)  # what the arm moved: seconds in motion, joint travel
    arm: str = ""  # the arm's state at the end
    seen: str = ""  # the job's own camera check after the release (`app.jobs.check`)
    candidates: list[dict] = field(default_factory=list)  # every pair the plan stage looked at (`choice.describe`)
    attempts: list[dict] = field(default_factory=list)  # one per grasp: its candidate and the outcome
    look: dict = field(default_factory=dict)  # the second look: points seen, the place it chose, how far it moved
    hole: dict = field(default_factory=dict)  # the handle hole seen in the cloud, if a hang looks for one
    info: dict = field(default_factory=dict)  # the cell's own facts (object, seed, ...)
    notes: list[str] = field(default_factory=list)  # what the job had to do beyond its plan (a jammed release)

    def record(self) -> dict:
        """JSON-ready."""
        return {"task": self.task, "method": self.method, "success": self.success, "failed_stage": self.failed_stage,
                "failure_kind": self.failure_kind, "reason": self.reason, "seconds": self.seconds,
                "total_seconds": round(sum(self.seconds.values()), 3),
                "poses": self.poses, "plan": self.plan, "motion": self.motion, "arm": self.arm, "seen": self.seen,
                "candidates": self.candidates,
                "attempts": self.attempts, "look": self.look, "hole": self.hole, "notes": self.notes, **self.info}


@contextmanager
def stage(result: JobResult, name: str, hooks: JobHooks):
    """Time a stage (summed over attempts); a failure in it, expected (`CellFailure`) or a bug, is
    recorded as the stage's and passes on."""
    start = time.perf_counter()
    try:
        yield
    except Exception:
        result.failed_stage = name
        raise
    finally:
        result.seconds[name] = round(result.seconds.get(name, 0.0) + time.perf_counter() - start, 3)
    hooks.keyframe(name)


def ur(T: np.ndarray) -> list[float]:
    """A pose as the record keeps it: UR's [x y z rx ry rz], rounded."""
    return np.round(pose_to_ur(T), 5).tolist()
