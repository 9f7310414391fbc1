"""Running eye-to-hand calibration on the simulated cell: mount the board, visit views, solve."""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from app.simcell.cell import SimCell
from calibration.board import BoardSpec
from calibration.eye_to_hand import CalibrationResult, aim_poses, collect, solve
from calibration.store import load_calibration, save_calibration
from hardware.robot_description import HOME_Q, cache_dir
from hardware.se3 import invert, make_pose, rotation_angle
from hardware.sim.flange_plate import FlangePlate

BOARD_OFFSET = 0.125  # m along tool0's z: the board plate sits just past the fingertips


@dataclass
class CellCalibration:
    """A calibration run on the sim cell, with the ground truth it is judged against."""

    result: CalibrationResult
    skipped: int
    seconds: float
    error_mm: float  # against the simulator's true camera pose
    error_deg: float


def calibrate_sim_cell(cell: SimCell, views: int = 20, seed: int = 0, spec: BoardSpec = BoardSpec()) -> CellCalibration:
    """Mount a ChArUco board on the flange, visit `views` poses facing the camera, solve."""
    t0 = time.perf_counter()
    texture = cache_dir() / "charuco" / f"board_{spec.squares[0]}x{spec.squares[1]}_{spec.square}.png"
    texture.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(texture), spec.image(2000))
    w, h = spec.size
    # board z (into the board) against tool z, centred on the tool axis
    T_tool0_plate = make_pose(np.diag([1.0, -1.0, -1.0]), [-w / 2, h / 2, BOARD_OFFSET])
    plate = FlangePlate(cell.robot, texture, spec.size, T_tool0_plate, cache_dir() / "charuco")
    try:
        poses = aim_poses(views, np.array(cell.config.camera_eye), np.random.default_rng(seed))
        observations, skipped = collect(cell.arm, cell.camera, poses, spec, cell.robot.kinematics.ik)
        result = solve(observations, cell.camera.intrinsics.matrix)
        cell.arm.moveJ(HOME_Q)
    finally:
        plate.remove()
    d = invert(cell.camera.T_base_cam) @ result.T_base_cam
    return CellCalibration(result, skipped, time.perf_counter() - t0, 1000 * float(np.linalg.norm(d[:3, 3])),
                           float(np.degrees(rotation_angle(d[:3, :3]))))


def result_record(c: CellCalibration) -> dict:
    """What the calibration file stores beside T_base_cam."""
    r = c.result
    return {"views": r.n_views, "skipped_views": c.skipped, "reprojection_rms_px": r.reprojection_rms_px,
            "hand_eye_residual_mm": r.residual_mm, "hand_eye_residual_deg": r.residual_deg,
            "T_tcp_board": r.T_tcp_board.tolist(), "seconds": c.seconds,
            "sim_truth_error_mm": c.error_mm, "sim_truth_error_deg": c.error_deg}


def ensure_calibration(cell, path: Path):
    """T_base_cam from the calibration file (never the simulator's truth); calibrate first if it is missing."""
    if not path.exists():
        print(f"no calibration file {path}: calibrating the cell first", file=sys.stderr)
        c = calibrate_sim_cell(cell)
        save_calibration(path, c.result.T_base_cam, result_record(c))
    return load_calibration(path)[0]
