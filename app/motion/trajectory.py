"""Joint trajectories: Ruckig rest-to-rest segments chained through waypoints, sampled for execution.

The free Ruckig computes state-to-state motions only (its intermediate-waypoint feature calls a
remote service and is never used here), so a path through waypoints here is a chain of time-optimal,
jerk-limited rest-to-rest segments - each segment is optimal, the chain stops at every waypoint (one
that does not stop: `app.motion.blend`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from ruckig import Trajectory

from hardware.interfaces import JointLimits
from hardware.motion_profile import ruckig_profile

SAMPLE_PERIOD = 1.0 / 250.0  # s between trajectory samples streamed to the arm


@dataclass
class JointTrajectory:
    """A timed joint path: times (T,) from 0, positions (T, D), velocities (T, D); accelerations (T, D)
    where the profile gave them."""

    times: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    label: str = ""
    qdd: np.ndarray | None = None

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    @property
    def end(self) -> np.ndarray:
        return self.q[-1]


def sample_profile(profile: Trajectory, period: float = SAMPLE_PERIOD) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(times (T,), positions (T, D), velocities (T, D)) of a Ruckig trajectory, both ends included."""
    times, q, qd, _ = sample_states(profile, period)
    return times, q, qd


def sample_states(profile: Trajectory, period: float = SAMPLE_PERIOD) -> tuple[np.ndarray, ...]:
    """(times (T,), positions, velocities, accelerations (T, D)) of a Ruckig trajectory, both ends included."""
    n = max(2, int(np.ceil(profile.duration / period)) + 1)
    times = np.linspace(0.0, profile.duration, n)
    states = [profile.at_time(t) for t in times]
    return times, *(np.array([s[k] for s in states]) for k in range(3))


def joint_segment(q0: np.ndarray, q1: np.ndarray, limits: JointLimits, speed: float = 1.05,
                  acceleration: float = 1.4, label: str = "", straight: bool = False) -> JointTrajectory:
    """One rest-to-rest joint motion, at most `speed` rad/s and `acceleration` rad/s^2 on any joint
    (ur_rtde's moveJ defaults) and never beyond the limits; `straight`: on the joint-space segment
    q0 -> q1 (`straight_segment`)."""
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    v_max, a_max = np.minimum(speed, limits.velocity), np.minimum(acceleration, limits.acceleration)
    if straight:
        return straight_segment(q0, q1, v_max, a_max, limits.jerk, label)
    times, q, qd, qdd = sample_states(ruckig_profile(q0, q1, v_max, a_max, limits.jerk))
    return JointTrajectory(times, q, qd, label, qdd)


def straight_segment(q0: np.ndarray, q1: np.ndarray, v_max: np.ndarray, a_max: np.ndarray, j_max: np.ndarray,
                     label: str = "") -> JointTrajectory:
    """The time-optimal rest-to-rest motion along the straight joint-space segment q0 -> q1 (a UR's moveJ;
    what a planner checked between its waypoints): a 1-D Ruckig profile of the arc length s in [0, L],

        q(t) = q0 + s(t) u,    u = (q1 - q0) / L,    limits on s: min_j (v_max,j, a_max,j, j_max,j) / |u_j|

    exactly on the segment (Ruckig's phase synchronisation falls back to time synchronisation, off the
    segment, where it finds no phase-synchronised profile)."""
    along = _along_segment(q0, q1, v_max, a_max, j_max)
    if along is None:
        return JointTrajectory(np.zeros(2), np.vstack([q0, q1]), np.zeros((2, len(q0))), label, np.zeros((2, len(q0))))
    u, profile = along
    times, s, sd, sdd = sample_states(profile)
    q = q0 + s * u  # (T, D): s is (T, 1)
    q[-1] = q1
    return JointTrajectory(times, q, sd * u, label, sdd * u)


def straight_duration(q0: np.ndarray, q1: np.ndarray, v_max: np.ndarray, a_max: np.ndarray, j_max: np.ndarray) -> float:
    """The duration (s) of `straight_segment`, without sampling it."""
    along = _along_segment(q0, q1, v_max, a_max, j_max)
    return 0.0 if along is None else float(along[1].duration)


def _along_segment(q0: np.ndarray, q1: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
                   j_max: np.ndarray) -> tuple[np.ndarray, Trajectory] | None:
    """The unit direction u (D,) of q0 -> q1 and the 1-D profile of s along it (`straight_segment`); None
    for a segment of no length."""
    length = float(np.linalg.norm(q1 - q0))
    if length < 1e-12:
        return None
    u = (q1 - q0) / length  # (D,)
    cap = [float(np.min(lim / np.maximum(np.abs(u), 1e-12))) for lim in (v_max, a_max, j_max)]
    return u, ruckig_profile(np.zeros(1), np.array([length]), *(np.array([c]) for c in cap))


def through_waypoints(waypoints: list[np.ndarray], limits: JointLimits, speed: float = 1.05,
                      acceleration: float = 1.4, label: str = "", straight: bool = False) -> JointTrajectory:
    """Chain rest-to-rest segments through joint waypoints into one trajectory (`straight`: each
    on its joint-space segment)."""
    if len(waypoints) < 2:
        raise ValueError("a trajectory needs at least two waypoints")
    parts = [joint_segment(a, b, limits, speed, acceleration, straight=straight)
             for a, b in zip(waypoints[:-1], waypoints[1:])]
    return concatenate(parts, label)


def concatenate(parts: list[JointTrajectory], label: str = "") -> JointTrajectory:
    """One trajectory of consecutive parts (each starts where the previous one ends, at rest)."""
    times, q, qd, qdd, offset = [], [], [], [], 0.0
    for i, part in enumerate(parts):
        skip = 0 if i == 0 else 1  # the joint sample is shared
        times.append(part.times[skip:] + offset)
        q.append(part.q[skip:])
        qd.append(part.qd[skip:])
        qdd.append(None if part.qdd is None else part.qdd[skip:])
        offset += part.duration
    accelerations = None if any(a is None for a in qdd) else np.concatenate(qdd)
    return JointTrajectory(np.concatenate(times), np.concatenate(q), np.concatenate(qd), label, accelerations)


def path_timing(q_path: np.ndarray, length: float, limits: JointLimits, speed: float, acceleration: float,
                jerk: float, label: str = "") -> JointTrajectory:
    """Time a geometric joint path q_path (K, D) (uniform in the path parameter s in [0, length])
    with a 1-D Ruckig profile on s, capped so that no joint exceeds its velocity or acceleration limit:

        dq/dt = q'(s) ds/dt,    d2q/dt2 = q'(s) d2s/dt2 + q''(s) (ds/dt)^2

    ds/dt <= v_j / max|q'_j|; each term of the acceleration gets half of a_j: d2s/dt2 <= a_j / (2 max|q'_j|),
    (ds/dt)^2 <= a_j / (2 max|q''_j|). The second bounds a line that bends sharply in joint space, as one
    near the wrist's singularity does (its wrist joints turn 2 rad over 10 cm)."""
    ds = length / max(len(q_path) - 1, 1)
    dq_ds = np.abs(np.diff(q_path, axis=0)) / max(ds, 1e-12)  # (K-1, D)
    worst = np.maximum(dq_ds.max(axis=0), 1e-9)  # (D,)
    bend = np.abs(np.diff(q_path, 2, axis=0)).max(axis=0, initial=0.0) / max(ds, 1e-12) ** 2  # (D,) max |q''|
    v = min(speed, float(np.min(limits.velocity / worst)),
            float(np.min(np.sqrt(limits.acceleration / (2.0 * np.maximum(bend, 1e-9))))))
    a = min(acceleration, float(np.min(limits.acceleration / (2.0 * worst))))
    s_grid = np.linspace(0.0, length, len(q_path))
    profile = ruckig_profile(np.zeros(1), np.array([length]), np.array([v]), np.array([a]), np.array([jerk]))
    times, s, sd = sample_profile(profile)
    s, sd = s[:, 0], sd[:, 0]
    q = interpolate_columns(s, s_grid, q_path)
    slope = interpolate_columns(s, s_grid[:-1], np.diff(q_path, axis=0) / np.diff(s_grid)[:, None])
    return JointTrajectory(times, q, slope * sd[:, None], label)


def interpolate_columns(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """(len(x), D): each column of fp (K, D), given at xp (K,), linearly interpolated at x."""
    return np.stack([np.interp(x, xp, fp[:, j]) for j in range(fp.shape[1])], axis=1)


def remainder(traj: JointTrajectory, q: np.ndarray, limits: JointLimits, speed: float = 0.5,
              acceleration: float = 1.0) -> JointTrajectory:
    """The rest of `traj` for an arm stopped at rest at q on (or near) its path: from q through the samples
    after the nearest one, resampled evenly along the joint-space path and timed again from rest
    (`path_timing`, on the path's joint-space length)."""
    k = int(np.abs(traj.q - q).max(axis=1).argmin())
    path = np.vstack([q, traj.q[k + 1:]]) if k + 1 < len(traj.q) else np.vstack([q, traj.end])  # (K, D)
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)  # (K-1,)
    length = float(steps.sum())
    if length < 1e-9:
        return JointTrajectory(np.zeros(2), np.vstack([q, q]), np.zeros((2, len(q))), traj.label)
    along = np.concatenate([[0.0], np.cumsum(steps)])  # (K,) a trajectory's samples are even in time, not in length
    even = np.linspace(0.0, length, len(path))
    path = interpolate_columns(even, along, path)
    return path_timing(path, length, limits, speed, acceleration, float(np.min(limits.jerk)), traj.label)


def reverse(traj: JointTrajectory) -> JointTrajectory:
    """The same path run backwards (a rest-to-rest profile is time-symmetric)."""
    qdd = None if traj.qdd is None else traj.qdd[::-1].copy()  # d2/dt2 q(T - t) = q''(T - t)
    return JointTrajectory(traj.times, traj.q[::-1].copy(), -traj.qd[::-1].copy(), traj.label, qdd)
