"""A joint path through waypoints without a stop at each: Ruckig through intermediate states.

The free Ruckig plans state to state, so the path is a chain of its motions, each from one waypoint
to the next, arriving there at a via velocity instead of at rest (and at zero acceleration). The via
velocity of joint j at an interior waypoint i is the lower of the peak speeds of the two straight
rest-to-rest segments that meet there - twice their mean, as in a triangular profile - in the
direction they share, within the speed limit, and zero where the joint turns back:

    v_ij = s_ij min(2 |dq_in,j| / T_in, 2 |dq_out,j| / T_out, v_max,j)   if s_ij = sign(dq_in,j) = sign(dq_out,j)
    v_ij = 0                                                              otherwise

(T: the segment's duration at rest at both ends; the factor 2: docs/decisions.md, "Blended transits"). Every motion stays within the velocity, acceleration
and jerk limits (Ruckig's), but leaves the straight joint segment the planner checked, cutting or
widening the corner. The caller's check (`blend_checked`) finds the first sample that fails - a
collision, a joint limit - and a waypoint at an end of its segment is then passed at rest, a segment
at rest at both ends on its straight line again; with every waypoint at rest the path is the
checked polyline itself. Ruckig's own intermediate-waypoint feature calls a remote service; the
time-optimal path parameterisation of a spline (toppra) bounds no jerk: hence this.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from app.motion.trajectory import JointTrajectory, concatenate, sample_states, straight_duration, straight_segment
from hardware.interfaces import JointLimits
from hardware.motion_profile import ruckig_profile


def via_velocities(waypoints: np.ndarray, durations: np.ndarray, v_max: np.ndarray,
                   rest: frozenset[int] = frozenset()) -> np.ndarray:
    """(K, D) velocities at the waypoints (K, D): the rule of the module's docstring; zero at both ends,
    at the waypoints in `rest`, and on the joints that turn back there. `durations` (K-1,): each straight
    segment's rest-to-rest time; `v_max` (D,): the speed limit."""
    steps = np.diff(waypoints, axis=0)  # (K-1, D)
    peak = np.minimum(2.0 * np.abs(steps) / np.maximum(durations, 1e-9)[:, None], v_max)  # (K-1, D)
    v = np.zeros_like(waypoints)
    for i in range(1, len(waypoints) - 1):
        if i in rest:
            continue
        same = np.sign(steps[i - 1]) * np.sign(steps[i]) > 0  # (D,)
        v[i] = np.where(same, np.sign(steps[i]) * np.minimum(peak[i - 1], peak[i]), 0.0)
    return v


def blended(waypoints: np.ndarray, limits: JointLimits, speed: float, acceleration: float, label: str = "",
            rest: frozenset[int] = frozenset()) -> tuple[JointTrajectory, np.ndarray]:
    """One trajectory through the waypoints (K, D), passing the interior ones at their via velocities
    (`via_velocities`), those in `rest` at rest on the straight segments; and the time (K,) it passes each."""
    waypoints = np.asarray(waypoints, float)
    v_max, a_max = np.minimum(speed, limits.velocity), np.minimum(acceleration, limits.acceleration)
    straight = [straight_duration(a, b, v_max, a_max, limits.jerk) for a, b in zip(waypoints[:-1], waypoints[1:])]
    v = via_velocities(waypoints, np.array(straight), v_max, rest)
    parts = []
    for i in range(len(waypoints) - 1):
        if not v[i].any() and not v[i + 1].any():  # a rest-to-rest segment keeps to its straight line
            parts.append(straight_segment(waypoints[i], waypoints[i + 1], v_max, a_max, limits.jerk, label))
            continue
        profile = ruckig_profile(waypoints[i], waypoints[i + 1], v_max, a_max, limits.jerk, v0=v[i], v1=v[i + 1])
        times, q, qd, qdd = sample_states(profile)
        parts.append(JointTrajectory(times, q, qd, label, qdd))
    passes = np.concatenate([[0.0], np.cumsum([p.duration for p in parts])])
    return concatenate(parts, label), passes


def blend_checked(waypoints: np.ndarray, limits: JointLimits, speed: float, acceleration: float, label: str,
                  first_bad: Callable[[JointTrajectory], float | None]) -> JointTrajectory:
    """`blended`, with a waypoint of the first failing segment passed at rest - the end nearer the failure
    first, the other if it fails again - again and again, until `first_bad(traj)` (the time (s) of its
    first sample that fails, None when none does) finds nothing, or the failing segment is already
    straight (the caller's own check then refuses it)."""
    interior = set(range(1, len(waypoints) - 1))
    rest: set[int] = set()
    while True:
        traj, passes = blended(waypoints, limits, speed, acceleration, label, frozenset(rest))
        bad = first_bad(traj)
        if bad is None:
            return traj
        k = int(np.clip(np.searchsorted(passes, bad, side="right") - 1, 0, len(waypoints) - 2))
        nearer = k if bad - passes[k] < passes[k + 1] - bad else k + 1
        ends = [i for i in (nearer, 2 * k + 1 - nearer) if i in interior - rest]
        if not ends:
            return traj
        rest.add(ends[0])
