"""Jobs against devices on the network (`nift run --devices net`): the unchanged job
(`app.jobs.job.run_job`) drives `NetArm`, `NetGripper` and `NetCamera`, found with zeroconf or at
given addresses; the served cell's test rig (kind "sim", `app.simcell.rig`) spawns each job's object
and judges it. Nothing here imports the simulator: the cell runs in `nift serve`'s process."""
from __future__ import annotations

import sys
import uuid
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from app.jobs.job import JobConfig, JobHooks, JobResult, run_job
from app.jobs.log import JobLog
from app.layout import CellLayout
from app.motion.scene import PlanningScene
from app.predict.methods import ORACLE
from app.predict.methods import method as method_record
from app.predict.predict import Prediction
from app.tasks.task import Task
from calibration.store import load_calibration, save_calibration
from hardware.net.client import NetArm, NetCamera, NetClient, NetDeviceConfig, NetGripper, open_client


@dataclass(frozen=True)
class NetCellConfig:
    """Where each device is (found by kind when no name or address is given)."""

    arm: NetDeviceConfig = NetDeviceConfig()
    gripper: NetDeviceConfig = NetDeviceConfig()
    camera: NetDeviceConfig = NetDeviceConfig()
    rig: NetDeviceConfig = field(default_factory=lambda: NetDeviceConfig(motion_timeout=600.0))


class NetCell:
    """The networked devices and the served cell's rig, connected together."""

    def __init__(self, config: NetCellConfig = NetCellConfig()) -> None:
        session = uuid.uuid4().hex[:12]  # one client to the server: the rig's verbs move the arm this session commands
        self.config = config = replace(config, **{k: replace(getattr(config, k), session=session)
                                                  for k in ("arm", "gripper", "camera", "rig")})
        self.arm, self.gripper, self.camera = NetArm(config.arm), NetGripper(config.gripper), NetCamera(config.camera)
        self.rig: NetClient | None = None

    def __enter__(self) -> "NetCell":
        try:
            for device in (self.arm, self.gripper, self.camera):
                device.connect()
            self.rig, _ = open_client(self.config.rig, "sim")
        except BaseException:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc) -> None:
        for device in (self.camera, self.gripper, self.arm):
            if device.is_connected:
                device.disconnect()
        if self.rig is not None:
            self.rig.call_quietly("release")
            self.rig.close()

    def rig_run(self, verb: str, *args):
        return self.rig.run(verb, *args, timeout=self.config.rig.motion_timeout)


class RigHooks(JobHooks):
    """The served rig's side of a job: let an arbitrary-pose object go once grasped; judge the place."""

    def __init__(self, cell: NetCell) -> None:
        self.cell = cell

    def on_grasped(self) -> None:
        self.cell.rig_run("grasped")

    def verify(self, seen: tuple[bool, str]) -> tuple[bool, str]:
        success, reason = self.cell.rig_run("verify")
        return bool(success), str(reason)


def remote_calibration(cell: NetCell, path: Path) -> np.ndarray:
    """T_base_cam from the calibration file; if it is missing, the served cell is calibrated and it is written."""
    if not path.exists():
        print(f"no calibration file {path}: calibrating the served cell first", file=sys.stderr)
        r = cell.rig_run("calibrate")
        save_calibration(path, np.asarray(r["T_base_cam"]), r["record"])
    return load_calibration(path)[0]


def _oracle(cell: NetCell) -> Callable[[np.ndarray], Prediction]:
    def predict(cloud: np.ndarray) -> Prediction:
        r = cell.rig_run("oracle")
        return Prediction(ORACLE, *(np.asarray(r[k]) for k in ("T_base_tcp", "T_base_fixture_seen", "motion")))
    return predict


def run_remote_series(cell: NetCell, layout: CellLayout, t: Task, seeds: list[int], pose: str, T_base_cam: np.ndarray,
                      config: JobConfig = JobConfig(), on_result: Callable[[JobResult], None] = lambda r: None,
                      scene: PlanningScene | None = None,
                      job_log: Callable[[int], JobLog | None] = lambda i: None) -> list[JobResult]:
    """One job per seed on the networked cell; the planning scene (`scene`, or one built here) is
    of `layout`, which must be the served cell's (the same --config on both sides); `job_log(i)` hears
    job i (the arm's state at each stage's end: a networked cell has no physics loop to sample)."""
    own = scene is None
    scene = PlanningScene(layout) if own else scene
    results = []
    try:
        for i, seed in enumerate(seeds):
            info = cell.rig_run("prepare", t.name, seed, pose)
            oracle = _oracle(cell) if method_record(config.method).true_poses else None
            try:
                result = run_job(t, cell.arm, cell.gripper, cell.camera, T_base_cam, layout.fixture_pose(t.fixture),
                                 scene, config, RigHooks(cell), oracle, job_log=job_log(i))
            finally:
                cell.rig_run("clear")
            result.info = {**info, "devices": "net"}
            results.append(result)
            on_result(result)
    finally:
        if own:
            scene.close()
    return results
