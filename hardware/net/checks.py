"""What a request's arguments must be before they reach a device: the right type and shape, finite,
within the arm's joint limits and workspace. Each check returns the clean value or raises
ValueError naming the argument and what was wrong."""
from __future__ import annotations

from typing import Any

import numpy as np

from hardware.interfaces import JointLimits

REACH = 1.5  # m: a TCP pose farther than this from the base is no UR5 pose
MAX_POINTS = 100_000  # trajectory samples
MAX_SPEED = 10.0  # rad/s or m/s, an upper bound on any speed argument
MAX_ACCELERATION = 100.0
MAX_FORCE = 1000.0  # N, an upper bound on a contact detection threshold


def vector(value: Any, n: int, what: str) -> np.ndarray:
    """A finite float vector of length n."""
    a = _array(value, what)
    if a.shape != (n,):
        raise ValueError(f"{what} must be {n} numbers, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{what} must be finite, got {np.round(a, 4).tolist()}")
    return a


def joints(value: Any, limits: JointLimits, what: str = "joint positions") -> np.ndarray:
    """Six finite joint positions inside the limits."""
    q = vector(value, 6, what)
    if not limits.contains(q):
        raise ValueError(f"{what} {np.round(q, 3).tolist()} are outside the joint limits")
    return q


def pose(value: Any, what: str = "TCP pose") -> np.ndarray:
    """A UR pose [x, y, z, rx, ry, rz], finite, within REACH of the base."""
    x = vector(value, 6, what)
    if np.linalg.norm(x[:3]) > REACH:
        raise ValueError(f"{what} {np.round(x[:3], 3).tolist()} is beyond the workspace ({REACH} m from the base)")
    return x


def number(value: Any, what: str, low: float, high: float) -> float:
    """A finite number in (low, high]."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or not low < value <= high:
        raise ValueError(f"{what} must be a number in ({low:g}, {high:g}], got {value!r}")
    return float(value)


def optional_number(value: Any, what: str, low: float, high: float) -> float | None:
    return None if value is None else number(value, what, low, high)


def trajectory(times: Any, q: Any, qd: Any, limits: JointLimits) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Increasing finite times (T,), joint positions (T, 6) inside the limits, velocities (T, 6) or None."""
    t, Q = _array(times, "trajectory times"), _array(q, "trajectory positions")
    if t.ndim != 1 or not 2 <= len(t) <= MAX_POINTS:
        raise ValueError(f"trajectory times must be 2 to {MAX_POINTS} numbers, got shape {t.shape}")
    if Q.shape != (len(t), 6):
        raise ValueError(f"trajectory positions must be ({len(t)}, 6), got {Q.shape}")
    if not (np.isfinite(t).all() and np.isfinite(Q).all()):
        raise ValueError("trajectory times and positions must be finite")
    if np.any(np.diff(t) <= 0):
        raise ValueError("trajectory times must increase")
    outside = np.flatnonzero(np.any((Q < limits.lower - 1e-9) | (Q > limits.upper + 1e-9), axis=1))  # (K,)
    if len(outside):
        raise ValueError(f"trajectory leaves the joint limits at sample {outside[0]} of {len(Q)}")
    implied_motion(t, Q, limits)
    if qd is None:
        return t, Q, None
    V = _array(qd, "trajectory velocities")
    if V.shape != Q.shape or not np.isfinite(V).all():
        raise ValueError(f"trajectory velocities must be finite ({len(t)}, 6), got {V.shape}")
    if np.any(np.abs(V) > limits.velocity * 1.05):
        raise ValueError("trajectory velocities exceed the joint velocity limits")
    return t, Q, V


def implied_motion(t: np.ndarray, Q: np.ndarray, limits: JointLimits, margin: float = 1.05) -> None:
    """Refuse samples (T,), (T, 6) whose own differences move a joint faster or accelerate it harder than
    its limits allow, whatever velocities came with them: a difference quotient is a weighted mean of
    the true velocity (acceleration) over its interval, so a path within the limits always passes."""
    dt = np.diff(t)  # (T-1,)
    V = np.diff(Q, axis=0) / dt[:, None]  # (T-1, 6) mean velocity per interval
    fast = np.argwhere(np.abs(V) > limits.velocity * margin)
    if len(fast):
        i, j = fast[0]
        raise ValueError(f"trajectory moves joint {j + 1} at {abs(V[i, j]):.3g} rad/s between samples {i} and "
                         f"{i + 1} (limit {limits.velocity[j]:.3g} rad/s)")
    if len(t) < 3:
        return
    A = np.diff(V, axis=0) / ((t[2:] - t[:-2]) / 2)[:, None]  # (T-2, 6) mean acceleration about each inner sample
    hard = np.argwhere(np.abs(A) > limits.acceleration * margin)
    if len(hard):
        i, j = hard[0]
        raise ValueError(f"trajectory accelerates joint {j + 1} at {abs(A[i, j]):.3g} rad/s^2 at sample {i + 1} "
                         f"(limit {limits.acceleration[j]:.3g} rad/s^2)")


def text(value: Any, what: str, choices: tuple[str, ...] | None = None) -> str:
    if not isinstance(value, str) or len(value) > 200 or (choices is not None and value not in choices):
        raise ValueError(f"{what} must be {'one of ' + ', '.join(choices) if choices else 'a short string'}, got {value!r}")
    return value


def integer(value: Any, what: str, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ValueError(f"{what} must be an integer in [{low}, {high}], got {value!r}")
    return value


def _array(value: Any, what: str) -> np.ndarray:
    if isinstance(value, np.ndarray):
        a = value
    elif isinstance(value, (list, tuple)) and len(value) <= MAX_POINTS * 6:
        try:
            a = np.array(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"{what} must be numbers") from None
    else:
        raise ValueError(f"{what} must be an array of numbers, got {type(value).__name__}")
    if a.dtype.kind not in "fiu":
        raise ValueError(f"{what} must be numbers, got {a.dtype}")
    return a.astype(np.float64)
