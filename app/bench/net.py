"""`nift bench-net`: the device servers against the in-process devices, on this machine's loopback.

    state read        getActualQ round trips, median and p99 (ms)
    streaming         joint states read per second, back to back
    depth frame       a 512 x 424 capture over the network, and the same capture in-process (ms):
                      their difference is the delivery
    job wall time     the same seeds in-process and against `nift serve` (s)
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from app.bench.served import served_cell
from app.jobs.job import JobConfig
from app.jobs.remote import NetCell, NetCellConfig, run_remote_series
from app.layout import CellLayout
from app.tasks.task import task
from hardware.net.client import NetClient, NetDeviceConfig
from hardware.net.token import read_token


def _ms(samples: list[float]) -> tuple[float, float]:
    a = 1000 * np.asarray(samples)
    return round(float(np.median(a)), 3), round(float(np.percentile(a, 99)), 3)


def _in_process(jobs: int, t, method: str, seed: int, T_base_cam: np.ndarray, frames: int) -> tuple[list, list]:
    from app.motion.scene import PlanningScene
    from app.sim.cell import CellConfig, SimCell
    from app.sim.jobs import JobSpec, run_sim_job

    walls, captures = [], []
    with SimCell(CellConfig()) as cell:
        for _ in range(frames):
            start = time.perf_counter()
            cell.camera.capture()
            captures.append(time.perf_counter() - start)
        scene = PlanningScene(CellConfig())
        try:
            for i in range(jobs):
                start = time.perf_counter()
                r = run_sim_job(cell, scene, T_base_cam, JobSpec(t, seed + i, "upright"), JobConfig(method=method))
                walls.append((time.perf_counter() - start, r.success))
        finally:
            scene.close()
    return walls, captures


def run_net_benchmark(reads: int, frames: int, jobs: int, task_name: str = "bowl", method: str = "nift",
                      seed: int = 0) -> dict:
    """The figures (see the module docstring)."""
    from calibration.store import load_calibration

    t = task(task_name)
    T_base_cam = load_calibration(Path("calibration.json"))[0]
    figures: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        token_file = Path(tmp) / "token"
        with served_cell(token_file, "--no-advertise") as (address, _):
            token = read_token(token_file)
            arm = NetClient(address, token, "arm")
            arm.call("getActualQ")
            lat = []
            for _ in range(reads):
                start = time.perf_counter()
                arm.call("getActualQ")
                lat.append(time.perf_counter() - start)
            figures["state_read_median_ms"], figures["state_read_p99_ms"] = _ms(lat)
            start, n = time.perf_counter(), 0
            while time.perf_counter() - start < 1.0:
                arm.call("getActualQ")
                n += 1
            figures["joint_state_stream_hz"] = round(n / (time.perf_counter() - start), 1)
            arm.close()
            device = NetDeviceConfig(address=address, token=token)
            with NetCell(NetCellConfig(device, device, device, NetDeviceConfig(address=address, token=token,
                                                                               motion_timeout=600.0))) as cell:
                shots = []
                for _ in range(frames):
                    start = time.perf_counter()
                    cell.camera.capture()
                    shots.append(time.perf_counter() - start)
                figures["depth_frame_net_median_ms"], figures["depth_frame_net_p99_ms"] = _ms(shots)
                net_walls = []
                if jobs:
                    def timed(r):
                        net_walls.append((time.perf_counter() - timed.start, r.success))
                        timed.start = time.perf_counter()
                    timed.start = time.perf_counter()
                    run_remote_series(cell, CellLayout(), t, [seed + i for i in range(jobs)], "upright", T_base_cam,
                                      JobConfig(method=method), timed)
    walls, captures = _in_process(jobs, t, method, seed, T_base_cam, frames)
    figures["depth_frame_in_process_median_ms"] = _ms(captures)[0]
    figures["depth_frame_delivery_ms"] = round(figures["depth_frame_net_median_ms"] - figures["depth_frame_in_process_median_ms"], 3)
    if jobs:
        figures["jobs"] = f"{jobs} {t.name} jobs, seeds {seed}-{seed + jobs - 1}, {method}"
        figures["job_wall_in_process_s"] = round(float(np.mean([w for w, _ in walls])), 2)
        figures["job_wall_net_s"] = round(float(np.mean([w for w, _ in net_walls])), 2)
        figures["job_net_slowdown"] = round(figures["job_wall_net_s"] / figures["job_wall_in_process_s"] - 1, 3)
        figures["success_in_process"] = f"{sum(s for _, s in walls)}/{jobs}"
        figures["success_net"] = f"{sum(s for _, s in net_walls)}/{jobs}"
    return figures
