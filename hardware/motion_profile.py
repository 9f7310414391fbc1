"""Time-optimal, jerk-limited rest-to-rest profiles (Ruckig), as a robot controller plans a moveJ.

The simulated arm's controller and the application's trajectory planner both use it, so it lives
in the hardware layer with no import of the application.
"""
from __future__ import annotations

import numpy as np
from ruckig import InputParameter, Result, Ruckig, Trajectory


class LineProfile:
    """A rest-to-rest motion from q0 to q1 on the straight joint line, q(t) = q0 + s(t) (q1 - q0),
    with s a 1-D time-optimal Ruckig profile from 0 to 1 under the tightest of the axes' limits,
    s_max = min_j limit_j / |q1_j - q0_j| (for velocity, acceleration and jerk): the limiting axis
    runs at its limits, as a UR's moveJ moves. Ruckig's own multi-axis synchronisation bends the
    path when the axes' jerk limits differ (38 mm off on a UR5 segment), and a planner's
    collision-free straight segment then collided once timed. `duration`, `at_time(t)` as Ruckig's."""

    def __init__(self, q0: np.ndarray, q1: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
                 j_max: np.ndarray) -> None:
        self.q0, self.delta = np.asarray(q0, float), np.asarray(q1, float) - np.asarray(q0, float)  # (D,)
        moving = np.abs(self.delta) > 0.0
        if not moving.any():
            self._s = _profile_1d(0.0, 1.0, 1.0, 1.0)  # no motion: zero duration
            return
        span = np.abs(self.delta[moving])

        def tightest(limit: np.ndarray) -> float:
            return float(np.min(np.asarray(limit, float)[moving] / span))

        self._s = _profile_1d(1.0, tightest(v_max), tightest(a_max), tightest(j_max))

    @property
    def duration(self) -> float:
        return float(self._s.duration)

    def at_time(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(positions, velocities, accelerations) (D,) each at time t."""
        s, sd, sdd = (float(x[0]) for x in self._s.at_time(t))
        return self.q0 + s * self.delta, sd * self.delta, sdd * self.delta


def _profile_1d(target: float, v: float, a: float, j: float) -> Trajectory:
    """Ruckig's time-optimal rest-to-rest profile of one axis from 0 to `target`."""
    inp = InputParameter(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [target], [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v], [a], [j]
    traj = Trajectory(1)
    result = Ruckig(1).calculate(inp, traj)
    if result not in (Result.Working, Result.Finished):
        raise ValueError(f"Ruckig could not plan the motion ({result})")
    return traj


def ruckig_profile(q0: np.ndarray, q1: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
                   j_max: np.ndarray) -> LineProfile:
    """Time-optimal jerk-limited rest-to-rest motion from q0 to q1 on the straight line (`LineProfile`)."""
    return LineProfile(q0, q1, v_max, a_max, j_max)
