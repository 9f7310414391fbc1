"""A teach-in session as a Rerun recording (`nift teach --web --rerun`): each operator step on a `step`
timeline (and `wall`, seconds since the session began), in the job's entity layout
(`app.recording.layout`, docs/recording.md): the arm's joints and TCP, the gripper's width, the
object's cloud as the camera saw it, each saved demo's grasp and place, and the step's answer as a
line of the stage log."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import rerun as rr

from app.recording import layout as L
from app.recording.robot import RobotModel
from hardware.se3 import invert, ur_to_pose


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
        self.rec.set_time("step", sequence=self.count)
        self.rec.set_time("wall", duration=time.perf_counter() - self.t0)
        self.rec.log(L.STAGES, rr.TextLog(f"{name}: {answer.message}", level="INFO" if answer.ok else "WARN"))
        arm = session.cell.arm
        q = np.asarray(arm.getActualQ(), float)
        for joint, value in zip(self.robot.joints, q):
            self.rec.log(f"{L.ROBOT}/joints/{joint.name}", joint.compute_transform(float(value), clamp=False))
        for j, value in enumerate(q):
            self.rec.log(f"{L.JOINTS}/j{j + 1}", rr.Scalars(float(value)))
        self.rec.log(L.GRIPPER_WIDTH, rr.Scalars(float(session.cell.gripper.width)))
        self.rec.log(L.GRIPPER_FORCE, rr.Scalars(float(session.cell.gripper.force)))
        T = ur_to_pose(arm.getActualTCPPose())
        self._world(L.TCP, rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]))
        taught = session.current
        if taught is not None and taught.cloud is not self.seen:
            self.seen = taught.cloud
            self._world(f"{L.CLOUD}/first_look", rr.Points3D(taught.cloud, radii=0.002))
        if name == "save_demo" and answer.ok and taught is not None and taught.saved:
            place = session.T_base_fixture @ taught.T_fixture_obj @ invert(taught.T_base_obj) @ taught.T_base_tcp
            for what, pose in (("grasp", taught.T_base_tcp), ("place", place)):
                self._world(f"world/demos/{taught.saved}/{what}", rr.LineStrips3D(L.gripper_outline(pose), colors=L.GREEN),
                            static=True)

    def close(self) -> None:
        self.rec.flush()
        self.rec.disconnect()

    def _world(self, path: str, archetype, static: bool = False) -> None:
        self.rec.log(path, rr.CoordinateFrame("base"), static=True)
        self.rec.log(path, archetype, static=static)


def session_path(out: Path, now: float | None = None) -> Path:
    """Where a session teaching into the demo folder `out` is recorded: beside it (the folder itself is
    swapped whole when a demo is saved), `<out>-session-<YYYYmmdd-HHMMSS>.rrd`."""
    stamp = time.strftime("%Y%m%d-%H%M%S", time.localtime(now))
    return out.parent / f"{out.name}-session-{stamp}.rrd"
