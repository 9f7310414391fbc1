"""A teach-in session as a Rerun recording (`nift teach --web --rerun`): each operator step on a `step`
timeline (and `wall`, seconds since the session began), in the job's entity layout
(`app.recording.layout`, docs/recording.md): the arm's joints and TCP, the gripper's width and force,
the force on the tool, the
object's cloud as the camera saw it, each saved demo's grasp and place, and the step's answer as a
line of the stage log."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import rerun as rr

from app.recording import layout as L
from app.recording.robot import RobotModel, log_in_base
from hardware.se3 import invert


class SessionRecording:
    """Writes a teach-in session to `path` (an .rrd file) as its steps happen; `step` is a session observer."""

    def __init__(self, path: Path) -> None:
        self.path, self.count, self.t0 = path, 0, time.perf_counter()
        self.rec = rr.RecordingStream("nift-cell-teach", recording_id=f"teach-{path.stem}")
        self.rec.save(path)
        self.rec.send_blueprint(L.blueprint("step"))
        self.robot = RobotModel()
        self.robot.log_model(self.rec)
        self.seen = None  # the cloud last logged

    def step(self, session, name: str, answer) -> None:
        """One operator step and its answer (`app.teach.session.Step`), with the cell's state after it."""
        self.count += 1
        wall = time.perf_counter() - self.t0
        self.rec.set_time("step", sequence=self.count)
        self.rec.set_time("wall", duration=wall)
        self.rec.log(L.STAGES, rr.TextLog(f"{name}: {answer.message}", level="INFO" if answer.ok else "WARN"))
        arm, gripper = session.cell.arm, session.cell.gripper
        now = [rr.TimeColumn("step", sequence=[self.count]), rr.TimeColumn("wall", duration=[wall])]
        self.robot.send_state(self.rec, now, np.asarray(arm.getActualQ(), float)[None],
                              np.asarray(arm.getActualTCPPose(), float)[None], np.array([gripper.width]),
                              np.array([gripper.force]), np.asarray(arm.getActualTCPForce(), float)[None])
        taught = session.current
        if taught is not None and taught.cloud is not self.seen:
            self.seen = taught.cloud
            log_in_base(self.rec, f"{L.CLOUD}/first_look", rr.Points3D(taught.cloud, radii=0.002))
        if name == "save_demo" and answer.ok and taught is not None and taught.saved:
            place = session.T_base_fixture @ taught.T_fixture_obj @ invert(taught.T_base_obj) @ taught.T_base_tcp
            for what, pose in (("grasp", taught.T_base_tcp), ("place", place)):
                log_in_base(self.rec, f"{L.DEMOS}/{taught.saved}/{what}",
                            rr.LineStrips3D(L.gripper_outline(pose), colors=L.GREEN), static=True)

    def close(self) -> None:
        self.rec.flush()
        self.rec.disconnect()


def session_path(out: Path, now: float | None = None) -> Path:
    """Where a session teaching into the demo folder `out` is recorded: beside it (the folder itself is
    swapped whole when a demo is saved), `<out>-session-<YYYYmmdd-HHMMSS>.rrd`."""
    stamp = time.strftime("%Y%m%d-%H%M%S", time.localtime(now))
    return out.parent / f"{out.name}-session-{stamp}.rrd"
