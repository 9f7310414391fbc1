"""`nift bench-net`: the device servers against the in-process devices, on this machine's loopback.

    state read        getActualQ round trips, median and p99 (ms)
    streaming         joint states read per second, back to back
    depth frame       delivering the last 512 x 424 RGB-D frame (depth float32 and colour, 1.5 MB)
                      over the network (ms); and a whole capture (render + delivery) over the
                      network against one in-process
    job wall time     the same seeds in-process and against `nift serve` (s)
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from app.bench.served import served_cell
from app.jobs.job import JobConfig
from app.jobs.remote import NetCell, NetCellConfig, run_remote_series
from app.layout import CellLayout
from app.tasks.task import task
from hardware.net.client import NetClient, NetDeviceConfig
from hardware.net.keys import client_keys


def _ms(samples: list[float]) -> tuple[float, float]:
    a = 1000 * np.asarray(samples)
    return round(float(np.median(a)), 3), round(float(np.percentile(a, 99)), 3)


def _timed(call: Callable[[], Any], n: int) -> tuple[list[float], Any]:
    """(seconds of each of n calls, the last call's value)."""
    seconds, value = [], None
    for _ in range(n):
        start = time.perf_counter()
        value = call()
        seconds.append(time.perf_counter() - start)
    return seconds, value


def _stage_medians(runs: list) -> dict[str, float]:
    stages = {k for _, _, seconds in runs for k in seconds}
    return {k: round(float(np.median([sec.get(k, 0.0) for _, _, sec in runs])), 3) for k in sorted(stages)}


def _paired_jobs(net: NetCell, local, t, method: str, seeds: list[int], T_base_cam: np.ndarray) -> tuple[list, list]:
    """Each seed's job over the network and in the in-process cell `local`, one planning scene for
    both, the order alternating from seed to seed (so neither always runs first):
    ([(wall s, success, stage seconds)] net, the same in-process)."""
    from app.motion.scene import PlanningScene
    from app.simcell.sim_job import JobSpec, run_sim_job

    remote, here = [], []
    scene = PlanningScene(local.config)
    try:
        for i, seed in enumerate(seeds):
            for where in ("net", "local") if i % 2 == 0 else ("local", "net"):  # each order half the time
                start = time.perf_counter()
                if where == "net":
                    [r] = run_remote_series(net, CellLayout(), t, [seed], "upright", T_base_cam,
                                            JobConfig.of(method), scene=scene)
                else:
                    r = run_sim_job(local, scene, T_base_cam, JobSpec(t, seed, "upright"), JobConfig.of(method))
                (remote if where == "net" else here).append((time.perf_counter() - start, r.success, r.seconds))
    finally:
        scene.close()
    return remote, here


def run_net_benchmark(reads: int, frames: int, jobs: int, task_name: str = "bowl", method: str = "nift",
                      seed: int = 0, calibration: Path = Path("calibration.json")) -> dict:
    """The figures (see the module docstring); the camera pose from the `calibration` file, the
    in-process cell calibrated first (and the file written) if it is missing."""
    from app.simcell.calibration import ensure_calibration
    from app.simcell.cell import CellConfig, SimCell

    t = task(task_name)
    figures: dict = {}
    with SimCell(CellConfig()) as local, tempfile.TemporaryDirectory() as tmp:
        T_base_cam = ensure_calibration(local, calibration)
        key_dir = Path(tmp) / "keys"
        with served_cell(key_dir, "--no-advertise") as (address, _):
            keys = client_keys(key_dir)
            arm = NetClient(address, keys, "arm")
            arm.call("getActualQ")
            lat, _ = _timed(lambda: arm.call("getActualQ"), reads)
            figures["state_read_median_ms"], figures["state_read_p99_ms"] = _ms(lat)
            start, n = time.perf_counter(), 0
            while time.perf_counter() - start < 1.0:
                arm.call("getActualQ")
                n += 1
            figures["joint_state_stream_hz"] = round(n / (time.perf_counter() - start), 1)
            arm.close()
            device = NetDeviceConfig(address=address, keys=key_dir)
            with NetCell(NetCellConfig(device, device, device, NetDeviceConfig(address=address, keys=key_dir,
                                                                               motion_timeout=600.0))) as cell:
                figures["capture_net_median_ms"] = _ms(_timed(cell.camera.capture, frames)[0])[0]
                camera = NetClient(address, keys, "camera")
                sent, frame = _timed(lambda: camera.call("last_frame"), frames)
                camera.close()
                if frame["depth"].shape != (424, 512):
                    raise RuntimeError(f"the served camera sent a {frame['depth'].shape} depth frame, not 424 x 512")
                figures["depth_frame_delivery_median_ms"], figures["depth_frame_delivery_p99_ms"] = _ms(sent)
                net_walls, walls = _paired_jobs(cell, local, t, method, [seed + i for i in range(jobs)], T_base_cam)
        figures["capture_in_process_median_ms"] = _ms(_timed(local.camera.capture, frames)[0])[0]
    if jobs:
        figures["jobs"] = f"{jobs} {t.name} jobs, seeds {seed}-{seed + jobs - 1}, {method}"
        figures["job_wall_in_process_s"] = round(float(np.mean([w for w, _, _ in walls])), 2)
        figures["job_wall_net_s"] = round(float(np.mean([w for w, _, _ in net_walls])), 2)
        figures["job_net_slowdown"] = round(figures["job_wall_net_s"] / figures["job_wall_in_process_s"] - 1, 3)
        figures["success_in_process"] = f"{sum(s for _, s, _ in walls)}/{jobs}"
        figures["success_net"] = f"{sum(s for _, s, _ in net_walls)}/{jobs}"
        figures["stage_median_seconds_in_process"] = _stage_medians(walls)
        figures["stage_median_seconds_net"] = _stage_medians(net_walls)
    return figures
