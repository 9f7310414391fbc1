"""SE(3) helpers, the bottom of the house: pose composition, inversion, rotation vectors, random rotations.

Pure numpy and SciPy; every layer may import it, the device layer and the method library included.

Conventions (docs/design.md): a pose is a 4x4 homogeneous float64 array; `T_a_b` maps coordinates
in frame b into frame a, so `T_a_c = T_a_b @ T_b_c`. At device boundaries poses may be UR-style
`[x, y, z, rx, ry, rz]` with a rotation vector (axis * angle, radians). Rotation maths is SciPy's
`Rotation`; this module only fixes the conventions around it.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = [
    "make_pose", "invert", "compose", "transform_points", "rotvec_to_matrix", "matrix_to_rotvec",
    "pose_to_ur", "ur_to_pose", "random_rotations", "random_poses", "rotation_angle", "pose_error",
    "interpolate_pose",
]


def make_pose(R: np.ndarray | None = None, t: np.ndarray | None = None) -> np.ndarray:
    """4x4 pose from a 3x3 rotation and a translation (identity where omitted)."""
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = np.asarray(R, dtype=np.float64)
    if t is not None:
        T[:3, 3] = np.asarray(t, dtype=np.float64)
    return T


def invert(T: np.ndarray) -> np.ndarray:
    """Inverse of a pose (or a stack of poses, (..., 4, 4)) using R^T, not a general inverse."""
    T = np.asarray(T, dtype=np.float64)
    R_t = np.swapaxes(T[..., :3, :3], -1, -2)
    out = np.zeros_like(T)
    out[..., :3, :3] = R_t
    out[..., :3, 3] = -(R_t @ T[..., :3, 3:4])[..., 0]
    out[..., 3, 3] = 1.0
    return out


def compose(*poses: np.ndarray) -> np.ndarray:
    """Product of poses left to right: compose(T_a_b, T_b_c) = T_a_c."""
    out = np.eye(4)
    for T in poses:
        out = out @ np.asarray(T, dtype=np.float64)
    return out


def transform_points(T: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply a pose to points: (N, 3) -> (N, 3)."""
    points = np.asarray(points)
    return points @ T[:3, :3].T + T[:3, 3]


def rotvec_to_matrix(rotvec: np.ndarray) -> np.ndarray:
    """Rotation vector(s) (..., 3) -> rotation matrices (..., 3, 3)."""
    return Rotation.from_rotvec(np.asarray(rotvec, dtype=np.float64)).as_matrix()


def matrix_to_rotvec(R: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) -> rotation vectors (..., 3), angle in [0, pi]."""
    return Rotation.from_matrix(np.asarray(R, dtype=np.float64)).as_rotvec()


def pose_to_ur(T: np.ndarray) -> np.ndarray:
    """4x4 pose -> UR-style [x, y, z, rx, ry, rz]."""
    return np.concatenate([T[:3, 3], matrix_to_rotvec(T[:3, :3])])


def ur_to_pose(p: np.ndarray) -> np.ndarray:
    """UR-style [x, y, z, rx, ry, rz] -> 4x4 pose."""
    p = np.asarray(p, dtype=np.float64)
    if p.shape != (6,):
        raise ValueError(f"a UR pose has 6 values [x, y, z, rx, ry, rz], got shape {p.shape}")
    return make_pose(rotvec_to_matrix(p[3:]), p[:3])


def random_rotations(n: int, rng: np.random.Generator) -> np.ndarray:
    """n rotation matrices drawn from the Haar (uniform) distribution on SO(3): (n, 3, 3)."""
    return Rotation.random(n, random_state=rng).as_matrix()


def random_poses(n: int, rng: np.random.Generator, translation_scale: float = 0.0) -> np.ndarray:
    """n poses with Haar rotations and translations uniform in [-s, s]^3: (n, 4, 4)."""
    T = np.tile(np.eye(4), (n, 1, 1))
    T[:, :3, :3] = random_rotations(n, rng)
    T[:, :3, 3] = rng.uniform(-translation_scale, translation_scale, size=(n, 3))
    return T


def rotation_angle(R: np.ndarray) -> np.ndarray:
    """Angle (radians) of rotation matrices (..., 3, 3), robust near 0 and pi."""
    return np.linalg.norm(matrix_to_rotvec(R), axis=-1)


def pose_error(T_a: np.ndarray, T_b: np.ndarray) -> tuple[float, float]:
    """(translation error in metres, rotation error in radians) between two poses."""
    dT = invert(T_a) @ T_b
    return float(np.linalg.norm(dT[:3, 3])), float(rotation_angle(dT[:3, :3]))


def interpolate_pose(T0: np.ndarray, T1: np.ndarray, s: float) -> np.ndarray:
    """Pose at fraction s in [0, 1] of the way from T0 to T1 (position lerp, rotation slerp)."""
    T = np.eye(4)
    T[:3, 3] = (1 - s) * T0[:3, 3] + s * T1[:3, 3]
    relative = Rotation.from_matrix(T0[:3, :3].T @ T1[:3, :3]).as_rotvec()
    T[:3, :3] = T0[:3, :3] @ Rotation.from_rotvec(s * relative).as_matrix()  # slerp: R0 exp(s log(R0^T R1))
    return T


def line_length(T0: np.ndarray, T1: np.ndarray, metres_per_radian: float = 0.1) -> float:
    """Path-parameter length of a straight TCP move: metres, with rotation counted at
    `metres_per_radian` as a floor so rotation-only moves get a length too."""
    distance = max(float(np.linalg.norm(T1[:3, 3] - T0[:3, 3])), 1e-9)
    return max(distance, metres_per_radian * float(rotation_angle(T0[:3, :3].T @ T1[:3, :3])))
