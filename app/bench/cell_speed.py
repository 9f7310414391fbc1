"""Cell benchmark: real-time factor, Kinect frame time, perception time, calibration error and time."""
from __future__ import annotations

import time

import numpy as np

from app.bench.geometry import best_time
from app.perception import object_cloud
from app.simcell.calibration import calibrate_sim_cell
from app.simcell.cell import CellConfig, SimCell
from app.simcell.spawn import spawn
from hardware.robot_description import HOME_Q


def run_cell_benchmark(quick: bool = False, seed: int = 0) -> dict:
    """Figures of the simulated cell as one flat dict (best of `repeats` for the timings)."""
    repeats = 2 if quick else 5
    with SimCell(CellConfig(camera_seed=seed)) as cell:
        t_sim0, t0 = cell.world.time, time.perf_counter()
        for delta in (0.5, -0.5):
            cell.arm.moveJ(HOME_Q + delta * np.array([1.0, 0.3, -0.3, 0.5, 0.5, 1.0]), speed=2.0, acceleration=4.0)
        rtf = (cell.world.time - t_sim0) / (time.perf_counter() - t0)
        spawn(cell.world, "mug", 100_001, "upright", rng=np.random.default_rng(seed))
        frame_s = best_time(cell.camera.capture, repeats)
        frame = cell.camera.capture()
        perception_s = best_time(lambda: object_cloud(frame, cell.camera.T_base_cam), repeats)
    with SimCell(CellConfig(camera_seed=seed)) as cell:
        calibration = calibrate_sim_cell(cell, views=12 if quick else 20, seed=seed)
    return {"quick": quick, "seed": seed, "real_time_factor_moveJ": rtf, "camera_frame_ms": 1000 * frame_s,
            "perception_ms": 1000 * perception_s, "calibration_views": calibration.result.n_views,
            "calibration_seconds": calibration.seconds, "calibration_error_mm": calibration.error_mm,
            "calibration_error_deg": calibration.error_deg,
            "calibration_reprojection_px": calibration.result.reprojection_rms_px}
