"""Eye-to-hand calibration: a fixed camera and a board on the flange -> T_base_cam.

The arm visits varied poses; at each the board is detected in the colour image (ChArUco, OpenCV)
giving T_cam_board_i, and the controller gives T_base_tcp_i. With the camera as OpenCV's "world"
and the board as its "camera", `cv2.calibrateRobotWorldHandEye` (Shah's method) solves
T_board_tcp . T_tcp_base_i = T_board_cam_i . T_cam_base for the two unknowns, both fixed:
T_cam_base (the camera pose) and T_board_tcp (how the board sits on the tool).
Only `Arm` and `DepthCamera` interfaces are used, so the same code runs on a real cell.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.optimize import least_squares

from calibration.board import BoardSpec, Detection, detect_board
from hardware.interfaces import Arm, DepthCamera
from hardware.se3 import (invert, make_pose, matrix_to_rotvec, random_rotations, rotation_angle, rotvec_to_matrix,
                          ur_to_pose)


@dataclass
class Observation:
    """One calibration view: the controller's TCP pose and the board detection."""

    T_base_tcp: np.ndarray
    detection: Detection

    @property
    def T_cam_board(self) -> np.ndarray:
        return self.detection.T_cam_board


@dataclass
class CalibrationResult:
    """The estimate and how well it explains the views."""

    T_base_cam: np.ndarray
    T_tcp_board: np.ndarray
    n_views: int
    reprojection_rms_px: float  # mean over views of the per-view RMS
    residual_mm: float  # mean |T_cam_board predicted - detected| translation
    residual_deg: float  # mean rotation difference
    per_view: list[dict] = field(default_factory=list)


def solve(observations: list[Observation], K: np.ndarray) -> CalibrationResult:
    """Robot-world/hand-eye solution from >= 3 views: Shah's closed form, then refined by
    minimising the reprojection error of every board corner in every view (SciPy least squares).
    A single view's PnP rotation is only good to ~1 degree at Kinect resolution; the corners
    themselves to ~0.3 px, so the joint refinement is what makes the result accurate."""
    if len(observations) < 3:
        raise ValueError(f"calibration needs at least 3 views with the board detected, got {len(observations)}")
    T_board_cam = [invert(o.T_cam_board) for o in observations]  # camera -> board ("world2cam")
    T_tcp_base = [invert(o.T_base_tcp) for o in observations]  # base -> tcp ("base2gripper")
    R_cb, t_cb, R_bt, t_bt = cv2.calibrateRobotWorldHandEye(
        [T[:3, :3] for T in T_board_cam], [T[:3, 3] for T in T_board_cam],
        [T[:3, :3] for T in T_tcp_base], [T[:3, 3] for T in T_tcp_base],
        method=cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH)
    T_cam_base = make_pose(R_cb, np.ravel(t_cb))  # "base2world": base -> camera
    T_board_tcp = make_pose(R_bt, np.ravel(t_bt))  # "gripper2cam": tcp -> board
    T_cam_base, T_tcp_board = refine(observations, K, T_cam_base, invert(T_board_tcp))
    per_view = []
    for o in observations:
        predicted = T_cam_base @ o.T_base_tcp @ T_tcp_board
        d = invert(predicted) @ o.T_cam_board
        per_view.append({"mm": 1000 * float(np.linalg.norm(d[:3, 3])),
                         "deg": float(np.degrees(rotation_angle(d[:3, :3]))),
                         "reprojection_px": _reprojection_rms(o, K, T_cam_base, T_tcp_board)})
    return CalibrationResult(invert(T_cam_base), T_tcp_board, len(observations),
                             float(np.mean([v["reprojection_px"] for v in per_view])),
                             float(np.mean([v["mm"] for v in per_view])), float(np.mean([v["deg"] for v in per_view])),
                             per_view)


def _pack(T_a: np.ndarray, T_b: np.ndarray) -> np.ndarray:
    return np.concatenate([matrix_to_rotvec(T_a[:3, :3]), T_a[:3, 3], matrix_to_rotvec(T_b[:3, :3]), T_b[:3, 3]])


def _unpack(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return make_pose(rotvec_to_matrix(x[:3]), x[3:6]), make_pose(rotvec_to_matrix(x[6:9]), x[9:12])


def _project(o: Observation, K: np.ndarray, T_cam_base: np.ndarray, T_tcp_board: np.ndarray) -> np.ndarray:
    """Board corners of a view projected through the calibration: (M, 2) pixels."""
    T = T_cam_base @ o.T_base_tcp @ T_tcp_board
    pc = o.detection.object_points @ T[:3, :3].T + T[:3, 3]
    uv = pc @ K.T
    return uv[:, :2] / uv[:, 2:3]


def _reprojection_rms(o: Observation, K, T_cam_base, T_tcp_board) -> float:
    err = _project(o, K, T_cam_base, T_tcp_board) - o.detection.image_points
    return float(np.sqrt(np.mean(np.sum(err ** 2, axis=1))))


def refine(observations: list[Observation], K: np.ndarray, T_cam_base: np.ndarray,
           T_tcp_board: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Minimise all corners' reprojection error over (T_cam_base, T_tcp_board)."""
    def residuals(x):
        a, b = _unpack(x)
        return np.concatenate([(_project(o, K, a, b) - o.detection.image_points).ravel() for o in observations])

    result = least_squares(residuals, _pack(T_cam_base, T_tcp_board), method="lm")
    return _unpack(result.x)


def aim_poses(n: int, look_at: np.ndarray, rng: np.random.Generator, centre=(0.58, 0.0, 0.33),
              spread=(0.06, 0.08, 0.05), max_tilt_deg: float = 20.0) -> list[np.ndarray]:
    """n TCP poses spread around `centre`, tool z pointing at `look_at` (the camera) within a tilt."""
    poses = []
    for R_tilt in random_rotations(n, rng):
        p = np.asarray(centre) + rng.uniform(-1, 1, 3) * np.asarray(spread)
        z = np.asarray(look_at) - p
        z /= np.linalg.norm(z)
        x = np.cross([0.0, 0.0, 1.0], z)
        x /= np.linalg.norm(x)
        R = np.column_stack([x, np.cross(z, x), z])
        # a rotation of at most max_tilt_deg: scale the Haar sample's rotation vector down
        v = matrix_to_rotvec(R_tilt)
        v *= np.radians(max_tilt_deg) * rng.uniform(0.3, 1.0) / max(np.linalg.norm(v), 1e-9)
        poses.append(make_pose(R @ rotvec_to_matrix(v), p))
    return poses


def collect(arm: Arm, camera: DepthCamera, poses_base_tcp: list[np.ndarray], spec: BoardSpec,
            ik, speed: float = 1.0) -> tuple[list[Observation], int]:
    """Visit poses (IK from `ik(T, q_seed) -> q or None`), detect the board; (views, skipped)."""
    views, skipped = [], 0
    for T in poses_base_tcp:
        q = ik(T, arm.getActualQ())
        if q is None:
            skipped += 1
            continue
        if not arm.moveJ(q, speed=speed):
            raise RuntimeError(f"calibration stopped: {arm.getLastError()} (moving to view {len(views) + skipped + 1})")
        frame = camera.capture()
        found = detect_board(frame.color, frame.intrinsics, spec)
        if found is None:
            skipped += 1
            continue
        views.append(Observation(ur_to_pose(arm.getActualTCPPose()), found))
    return views, skipped
