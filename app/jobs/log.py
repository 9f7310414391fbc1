"""What a job tells an observer as it runs: its stages, each look, the plan it chose, the arm's state,
and its record at the end. `JobLog` keeps nothing, so a job without `--rerun` does no work for it;
`app.recording.job_log.RerunJobLog` writes all of it to a Rerun recording (docs/recording.md).

Time: the log reads `clock()` (the arm's controller clock, `Arm.getTimestamp`) when it writes, so a
job that is not logged never asks for it.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Callable

import numpy as np

from hardware.interfaces import Frame

if TYPE_CHECKING:  # the types of the arguments only: this module imports nothing of the job's
    from app.jobs.record import JobResult
    from app.motion.planner import PickPlacePlan
    from app.predict.pairs import Candidate
    from app.predict.predict import Prediction
    from app.tasks.task import Task
    from hardware.kinematics import UR5Kinematics


class JobLog:
    """A job's observer; every method does nothing here, and a job asks nothing of its devices for it."""

    active = False  # whether the job should read its devices' state for this log

    def begin(self, t: Task, method: str, clock: Callable[[], float]) -> None:
        """The job starts: its task, its method, and the clock its events are stamped with."""

    def fixtures(self, meshes: list) -> None:
        """The cell's fixtures (trimesh meshes, base frame), once per job."""

    def stage(self, name: str, event: str) -> None:
        """Stage `name` "started", "ended" or "failed"."""

    def look(self, frame: Frame, T_base_cam: np.ndarray) -> None:
        """A camera frame, and the camera's pose (4, 4) in the base frame."""

    def cloud(self, points: np.ndarray, label: str = "first look") -> None:
        """The object's points (N, 3) in the base frame, as the job perceived them in the look `label`."""

    def prediction(self, pred: Prediction) -> None:
        """The method's grasp and place for the last cloud."""

    def chosen(self, candidate: Candidate, plan: PickPlacePlan, kin: UR5Kinematics) -> None:
        """The pair the job will execute, its planned segments, and the arm's kinematics (its TCP)."""

    def arm_state(self, q: np.ndarray, tcp: np.ndarray, width: float, grip: float, tool_force: np.ndarray) -> None:
        """The arm's joints (6,), TCP pose (UR [x y z rx ry rz]), the gripper's width (m) and force (N),
        and the force on the tool (6,), now."""

    def end(self, result: JobResult) -> None:
        """The job's record, once it has ended (failed or not)."""


class LoggedCamera:
    """The job's camera, each frame it captures handed to the log too (every look, the second and the
    verifying one included)."""

    def __init__(self, camera, log: JobLog, T_base_cam: np.ndarray) -> None:
        self.camera, self.log, self.T_base_cam = camera, log, T_base_cam

    def __getattr__(self, name: str):
        return getattr(self.camera, name)

    def capture(self) -> Frame:
        frame = self.camera.capture()
        self.log.look(frame, self.T_base_cam)
        return frame
