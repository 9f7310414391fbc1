"""Lines under contact detection: the approach, the place, the search for the place and the way out of a
hang (our addition).

A line runs with the arm's contact detection on (ur_rtde's `startContactDetection`): a change of
the force on the tool stops the arm at rest, rather than pressing on into a protective stop.

The place line of a mug threads its handle onto the rack's peg. The hole comes from the cloud, a
centimetre or two off, and the mug may have turned a few degrees in the grasp: the peg's tip then
meets the handle or the wall 5-8 cm before the place, where an unguarded line ends in a protective
stop (docs/jobs.md). A person would back off and try again a little to the side,
as a robot threads a peg into a hole (a search about the nominal line, as in assembly):

    T_k = T_place + r_k (cos(phi_k) u + sin(phi_k) v),    u, v _|_ d, d the line's direction,

for rings of radius r_k about the line, each run from its own pre-place (the pre-place shifted as
much) under contact detection, until one gets within `PLACE_ARRIVED` of its end.

Let go, the mug swings onto the peg, and may swing into the fingers that held it: the way out of a
predicted hang is guarded too (`guarded_leave`).
"""
from __future__ import annotations

import numpy as np

from app.failures import ContactStop, ExecutionFailure
from app.jobs.context import JobContext
from app.motion.executor import execute, motion_failure
from app.motion.trajectory import remainder
from hardware.se3 import make_pose, pose_to_ur

PLACE_ARRIVED = 0.03  # m: a place line stopped by a contact this close to its place lets go there
SET_DOWN_ARRIVED = 0.05  # m: an object set down on a shelf that meets the board this close to its place is let go
# there (a predicted place a few centimetres too low pressed a tall bottle into the board: a protective stop)
SEARCH_RINGS = ((0.006, 6), (0.012, 8), (0.018, 10))  # (radius m, offsets on the ring) tried about the place line
SEARCH_SPEED, SEARCH_ACCELERATION = 0.1, 0.5  # m/s, m/s^2 of the search's lines


def guarded_line(job: JobContext, line, force: float) -> tuple[float | None, str]:
    """Execute a joint trajectory under contact detection at `force` N: (None, '') when it got to its
    end; (how far (m) the TCP stopped short of it, why) when a contact stopped it; ExecutionFailure for
    any other stop."""
    job.arm.startContactDetection(force)
    try:
        execute(job.arm, line, job.config.motion.end_tolerance)
        return None, ""
    except ExecutionFailure as exc:
        if not job.arm.readContactDetection():
            raise
        return _short_of(job, job.kin.fk(line.end)), str(exc)
    finally:
        job.arm.stopContactDetection()


def guarded_place(job: JobContext, place) -> bool:
    """The place line under contact detection; a contact within `PLACE_ARRIVED` of the place lets go
    there, one farther out starts the search (`search_place`). Whether the arm stopped off the planned
    place (the way out is then planned from where it is)."""
    met, why = guarded_line(job, place, job.config.place_contact_force)
    if met is None:
        return False
    if met > PLACE_ARRIVED:
        met = search_place(job, job.kin.fk(place.q[0]), job.kin.fk(place.end), met, why)
    if met > 0.0:
        job.result.notes.append(f"place: the held object met the fixture {1000 * met:.0f} mm before its place; "
                                "let go there")
    return True


def guarded_set_down(job: JobContext, place) -> bool:
    """A predicted place on a shelf, under contact detection: the held object meeting the board within
    `SET_DOWN_ARRIVED` of the place is let go there (ContactStop farther out: it met something else).
    Whether the arm stopped off the planned place."""
    met, why = guarded_line(job, place, job.config.place_contact_force)
    if met is None:
        return False
    if met > SET_DOWN_ARRIVED:
        raise ContactStop(f"place: the held object met something {1000 * met:.0f} mm before its place ({why})")
    job.result.notes.append(f"place: the held object met the shelf {1000 * met:.0f} mm before its place; let go there")
    return True


def guarded_leave(job: JobContext, leave: list) -> None:
    """Retreat, clear and go home (`leave`: their trajectories). A predicted hang's way out (`JobContext.guards_hang`)
    runs under contact detection: fingers that meet the mug they let go (which an unguarded way out drags
    into a protective stop) stop the arm at rest, the gripper opens fully (2 cm more on
    each side), and the arm carries on along the planned way out from where it stopped."""
    tolerance = job.config.motion.end_tolerance
    if not job.guards_hang():
        for segment in leave:
            execute(job.arm, segment, tolerance)
        return
    for i, segment in enumerate(leave):
        met, why = guarded_line(job, segment, job.config.leave_contact_force)
        if met is not None:
            job.gripper.open(width=job.gripper.stroke)
            job.result.notes.append(f"{segment.label}: the fingers met something ({why}); opened fully and "
                                    "carried on")
            execute(job.arm, remainder(segment, job.arm.getActualQ(), job.arm.joint_limits), tolerance)
            for rest in leave[i + 1:]:
                execute(job.arm, rest, tolerance)
            return


def search_place(job: JobContext, T_pre: np.ndarray, T_place: np.ndarray, met: float, why: str) -> float:
    """The place line shifted about its nominal one (the module's docstring) until a shifted line gets
    within `PLACE_ARRIVED` of its end: how far short it stopped; ContactStop, the arm at rest at the
    pre-place, when none does."""
    offsets = search_offsets(T_place[:3, 3] - T_pre[:3, 3])
    tried = np.zeros(3)  # the offset of the line that last met something
    for offset in offsets:
        _move(job, _moved(T_pre, tried), "backing off to the pre-place")  # back along the line that met it
        _move(job, _moved(T_pre, offset), "the move aside")
        tried = offset
        job.arm.startContactDetection(job.config.place_contact_force)
        try:
            arrived = job.arm.moveL(pose_to_ur(_moved(T_place, offset)), SEARCH_SPEED, SEARCH_ACCELERATION)
            stopped = not arrived and job.arm.readContactDetection()
        finally:
            job.arm.stopContactDetection()
        if not arrived and not stopped:
            raise motion_failure(job.arm, "place: the search's line")
        short = 0.0 if arrived else _short_of(job, _moved(T_place, offset))
        job.result.notes.append(f"place: a line {1000 * np.linalg.norm(offset):.0f} mm aside "
                                f"{'got there' if arrived else f'met something {1000 * short:.0f} mm short'}")
        if short <= PLACE_ARRIVED:
            return short
    _move(job, _moved(T_pre, tried), "backing off to the pre-place")
    _move(job, T_pre, "the move back")
    raise ContactStop(f"place: the held object met something {1000 * met:.0f} mm before its place ({why}), "
                    f"and on each of {len(offsets)} lines beside it")


def search_offsets(direction: np.ndarray) -> list[np.ndarray]:
    """(3,) offsets about a line along `direction`: rings of SEARCH_RINGS in the plane across it."""
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    u = np.cross(d, [0.0, 0.0, 1.0] if abs(d[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    return [r * (np.cos(phi) * u + np.sin(phi) * v) for r, n in SEARCH_RINGS
            for phi in np.linspace(0.0, 2 * np.pi, n, endpoint=False)]


def _moved(T: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """The pose T with its position moved by offset (3,), its rotation the same."""
    return make_pose(T[:3, :3], T[:3, 3] + offset)


def _move(job: JobContext, T: np.ndarray, what: str) -> None:
    if not job.arm.moveL(pose_to_ur(T), SEARCH_SPEED, SEARCH_ACCELERATION):
        raise motion_failure(job.arm, f"place: {what}")


def _short_of(job: JobContext, T_end: np.ndarray) -> float:
    """How far (m) the TCP is from T_end's position."""
    return float(np.linalg.norm(job.kin.fk(job.arm.getActualQ())[:3, 3] - T_end[:3, 3]))
