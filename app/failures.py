"""How a job's stages fail, typed: what the cell could not do, as opposed to a bug of ours.

    CellFailure                      every failure a job expects; its `kind` goes in the record
    |- PerceptionFailure             the camera does not show what the stage needs
    |  |- ObjectNotSeen              no object in the workspace, or the held object out of view
    |  `- BadFrame                   a depth frame no driver should send (wrong size, NaN, all invalid)
    |- PlanningFailure               no motion was found; the arm has not moved for it
    |  |- NoIKSolution               no collision-free joint configuration reaches a pose
    |  |- NoPath                     the sampling planner found no collision-free transit
    |  |- PathCollides               a path was found but collides (once timed, or along a line)
    |  |- OutOfJointLimits           a joint would leave its limits (the wrist's turn of the second look)
    |  `- NoCandidate                none of the candidate pairs could be planned (`tried` says why each)
    |     `- NoDemoLikeGrasp         no grasp like the demos' exists in this pose (counted apart)
    |- ExecutionFailure              a motion did not complete; the arm is stopped
    |  |- ProtectiveStop             the controller's protective stop
    |  |- ContactStop                contact detection stopped a guarded motion where no contact may be
    |  |- MotionStopped              any other stop, or a motion that ended off its target
    |  `- ReleaseJammed              the fingers did not open off the object
    |- GraspMissed                   the gripper holds nothing after closing, or met the object on the way in
    |  `- GraspSlipped               it held the object after closing and lost it in the lift, the look or the carry
    |- PlaceMissed                   the camera sees nothing new where the object was sent: it fell
    `- PlaceFailed                   the cell's verdict on the place is no

A device whose controller stopped answering (`hardware.interfaces.DeviceConnectionLost`) ends the job
as `CONNECTION_LOST`, naming the stage and the lost server, with no clean-up tried. Anything else raised
inside a job is a bug: the job ends as an internal error (`INTERNAL_ERROR`), its traceback goes to the
log, and the benchmarks count it apart (`app.jobs.job.run_job`).
"""
from __future__ import annotations

from typing import ClassVar

INTERNAL_ERROR = "internal_error"  # the record's kind for an exception that is no CellFailure
CONNECTION_LOST = "connection_lost"  # the record's kind when a device's controller stopped answering


class CellFailure(Exception):
    """A failure a job expects; `kind` names its class in records (stable across message changes)."""

    kind: ClassVar[str] = "failure"


class PerceptionFailure(CellFailure):
    kind = "perception"


class ObjectNotSeen(PerceptionFailure):
    kind = "object_not_seen"


class BadFrame(PerceptionFailure):
    kind = "bad_frame"


class PlanningFailure(CellFailure):
    kind = "planning"


class NoIKSolution(PlanningFailure):
    kind = "no_ik"


class NoPath(PlanningFailure):
    kind = "no_path"


class PathCollides(PlanningFailure):
    kind = "path_collides"


class OutOfJointLimits(PlanningFailure):
    kind = "out_of_joint_limits"


class NoCandidate(PlanningFailure):
    """No candidate pair could be planned; `tried` holds the record's line for each pair looked at."""

    kind = "no_candidate"

    def __init__(self, message: str, tried: list[dict] | None = None) -> None:
        super().__init__(message)
        self.tried = tried or []


class NoDemoLikeGrasp(NoCandidate):
    kind = "no_demo_like_grasp"


class ExecutionFailure(CellFailure):
    kind = "execution"


class ProtectiveStop(ExecutionFailure):
    kind = "protective_stop"


class ContactStop(ExecutionFailure):
    kind = "contact_stop"


class MotionStopped(ExecutionFailure):
    kind = "motion_stopped"


class ReleaseJammed(ExecutionFailure):
    kind = "release_jammed"


class GraspMissed(CellFailure):
    kind = "grasp_missed"


class GraspSlipped(GraspMissed):
    """The object was held after closing and slid out later: the next grasp keeps away from this one."""

    kind = "grasp_slipped"


class PlaceMissed(CellFailure):
    kind = "place_missed"


class PlaceFailed(CellFailure):
    kind = "place_failed"


def kinds() -> dict[str, type[CellFailure]]:
    """Every failure kind -> its class (the record's `failure_kind` values, less `INTERNAL_ERROR`)."""
    found, todo = {}, [CellFailure]
    while todo:
        cls = todo.pop()
        found[cls.kind] = cls
        todo += cls.__subclasses__()
    return found
