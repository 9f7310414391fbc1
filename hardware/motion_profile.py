"""Time-optimal, jerk-limited profiles (Ruckig), at rest or through a via velocity, as a robot controller plans a moveJ.

The simulated arm's controller and the application's trajectory planner both use it, so it lives
in the hardware layer with no import of the application.
"""
from __future__ import annotations

import numpy as np
from ruckig import InputParameter, Result, Ruckig, Trajectory


def ruckig_profile(q0: np.ndarray, q1: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
                   j_max: np.ndarray, v0: np.ndarray | None = None, v1: np.ndarray | None = None) -> Trajectory:
    """Time-optimal jerk-limited trajectory from q0 to q1 (Ruckig, offline, every joint arriving together),
    at rest at both ends unless the velocities `v0`, `v1` are given (a motion through a via point), at
    zero acceleration there. Its path leaves the straight joint segment; one that keeps to it:
    `app.motion.trajectory.straight_segment`."""
    dof = len(q0)
    rest = [0.0] * dof
    inp = InputParameter(dof)
    inp.current_position, inp.current_velocity, inp.current_acceleration = list(q0), _list(v0, dof), rest
    inp.target_position, inp.target_velocity, inp.target_acceleration = list(q1), _list(v1, dof), rest
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = list(v_max), list(a_max), list(j_max)
    traj = Trajectory(dof)
    result = Ruckig(dof).calculate(inp, traj)
    if result not in (Result.Working, Result.Finished):
        raise ValueError(f"Ruckig could not plan the motion ({result})")
    return traj


def _list(v: np.ndarray | None, dof: int) -> list[float]:
    return [0.0] * dof if v is None else [float(x) for x in v]
