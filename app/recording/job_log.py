"""`RerunJobLog`: a job written to a Rerun recording as it runs (`nift run --rerun`), in the entity
layout of `app.recording.layout` (docs/recording.md), on two timelines: `sim`, the arm's controller
clock (s), and `wall`, seconds since the job began (imitation and planning take wall time while the
controller's clock stands still).

Events (stages, looks, the prediction, the plan) are logged as they happen. The arm's state comes in
as samples (each stage's end, and every physics step's sample in the simulated cell,
`app.simcell.sampling`); they are kept and sent as columns at the end, one call per entity, so a
recorded job costs little more than an unrecorded one.
"""
from __future__ import annotations

import json
import sys
import time
import uuid
from pathlib import Path
from typing import Callable

import numpy as np
import rerun as rr

from app.jobs.log import JobLog
from app.recording import layout as L
from app.recording.robot import RobotModel, log_in_base
from hardware.interfaces import Frame
from hardware.se3 import transform_points, ur_to_pose


class RerunJobLog(JobLog):
    """Writes one job to `path` (an .rrd file), or to a viewer it spawns when `path` is None."""

    active = True

    def __init__(self, path: Path | None, name: str = "job") -> None:
        self.rec = rr.RecordingStream("nift-cell", recording_id=f"{name}-{uuid.uuid4().hex[:8]}")
        if path is None:
            spawn_viewer(self.rec)
        else:
            self.rec.save(path)
        self.rec.send_blueprint(L.blueprint())
        self.clock: Callable[[], float] = lambda: 0.0
        self.t0 = time.perf_counter()
        self.samples: list[tuple[float, float, np.ndarray, np.ndarray, float, float, np.ndarray]] = []
        self.templates: dict[str, np.ndarray] = {}

    # the job's events ------------------------------------------------------------------------
    def begin(self, t, method: str, clock: Callable[[], float]) -> None:
        self.clock, self.t0 = clock, time.perf_counter()
        self.rec.send_property("job", rr.AnyValues(task=t.name, method=method))
        self.robot = RobotModel()
        self.robot.log_model(self.rec)
        self.templates = _template_points(t, method)
        self._now()
        self.rec.log(L.STAGES, rr.TextLog(f"job: {t.name} by {method}"))

    def fixtures(self, meshes: list) -> None:
        for i, mesh in enumerate(meshes):
            self._world(f"{L.FIXTURES}/{i}", rr.Mesh3D(vertex_positions=mesh.vertices, triangle_indices=mesh.faces,
                                                       vertex_normals=mesh.vertex_normals, albedo_factor=L.FIXTURE_COLOUR),
                        static=True)

    def stage(self, name: str, event: str) -> None:
        self._now()
        self.rec.log(L.STAGES, rr.TextLog(f"{name} {event}", level="ERROR" if event == "failed" else "INFO"))

    def look(self, frame: Frame, T_base_cam: np.ndarray) -> None:
        self._now()
        self.rec.log(f"{L.IMAGES}/image", rr.Image(frame.color))
        self.rec.log(f"{L.IMAGES}/depth", rr.DepthImage(frame.depth, meter=1.0))
        eye = T_base_cam[:3, 3]
        self._world(L.CAMERA, rr.Arrows3D(origins=[eye], vectors=[0.2 * T_base_cam[:3, 2]], labels=["camera"]))

    def cloud(self, points: np.ndarray, label: str = "first look") -> None:
        self._now()
        self._world(f"{L.CLOUD}/{label.replace(' ', '_')}", rr.Points3D(points, radii=0.002))

    def prediction(self, pred) -> None:
        self._now()
        for name, T in (("grasp", pred.T_base_tcp), ("place", pred.T_base_tcp_place)):
            self._world(f"{L.PREDICTION}/{name}", rr.LineStrips3D(L.gripper_outline(T), colors=L.GREY))

    def chosen(self, candidate, plan, kin) -> None:
        self._now()
        for name, T in (("grasp", plan.T_base_grasp), ("place", plan.T_base_place)):
            if T is not None:
                self._world(f"{L.PLAN}/{name}", rr.LineStrips3D(L.gripper_outline(T), colors=L.BLUE))
        for segment in plan.segments:
            tcp = np.array([kin.fk(q)[:3, 3] for q in segment.q[:: max(1, len(segment.q) // 50)]])  # (<=50, 3)
            self._world(f"{L.PLAN}/path/{segment.label.replace(' ', '_')}", rr.LineStrips3D([tcp], colors=L.BLUE))
        self._log_nit(candidate)

    def arm_state(self, q: np.ndarray, tcp: np.ndarray, width: float, grip: float, tool_force: np.ndarray) -> None:
        self.samples.append((self.clock(), time.perf_counter() - self.t0, np.asarray(q, float).copy(),
                             np.asarray(tcp, float).copy(), float(width), float(grip), np.asarray(tool_force, float).copy()))

    def end(self, result) -> None:
        self._now()
        self._send_samples()
        for i, c in enumerate(result.candidates):
            strips = L.gripper_outline(ur_to_pose(c["grasp"])) + L.gripper_outline(ur_to_pose(c["place"]))
            path = f"{L.CANDIDATES}/{i:03d}"
            self._world(path, rr.LineStrips3D(strips, colors=L.outcome_colour(c["outcome"])), static=True)
            self.rec.log(path, rr.AnyValues(outcome=c["outcome"], score=c["score"], grasp_rank=c["grasp_rank"],
                                            place_rank=c["place_rank"]), static=True)
        verdict = "succeeded" if result.success else f"failed at {result.failed_stage} ({result.failure_kind}): {result.reason}"
        self.rec.log(L.VERDICT, rr.TextDocument(f"{result.task} by {result.method}: {verdict}\n\n"
                                                f"```json\n{json.dumps(result.record(), indent=1, default=str)}\n```",
                                                media_type="text/markdown"))
        self.rec.flush()
        self.rec.disconnect()

    # helpers ---------------------------------------------------------------------------------
    def _now(self) -> None:
        """Set both timelines to now."""
        self.rec.set_time("sim", duration=float(self.clock()))
        self.rec.set_time("wall", duration=time.perf_counter() - self.t0)

    def _world(self, path: str, archetype, static: bool = False) -> None:
        log_in_base(self.rec, path, archetype, static)

    def _log_nit(self, candidate) -> None:
        """The templates' query points at the chosen pair: the grasp's in the TCP frame at the grasp, the
        place's in the frame of the fixture the object is placed on."""
        for name, T in (("grasp", candidate.T_base_tcp), ("place", candidate.T_base_fixture)):
            if name in self.templates:
                self._world(f"{L.NIT}/{name}", rr.Points3D(transform_points(T, self.templates[name]), radii=0.003,
                                                          colors=L.GREEN if name == "grasp" else L.BLUE))

    def _send_samples(self) -> None:
        if not self.samples:
            return
        sim, wall, q, tcp, width, grip, force = (np.array(v) for v in zip(*self.samples))
        times = [rr.TimeColumn("sim", duration=sim), rr.TimeColumn("wall", duration=wall)]
        self.robot.send_state(self.rec, times, q, tcp, width, grip, force)


def spawn_viewer(rec: rr.RecordingStream) -> None:
    """Stream `rec` to a Rerun viewer started now: the `rerun` installed beside this Python (the venv's
    bin, which need not be on PATH), else the one on PATH; a one-line error when there is none."""
    beside = Path(sys.executable).parent / "rerun"
    try:
        rr.spawn(executable_path=str(beside) if beside.exists() else None, recording=rec)
    except RuntimeError as exc:
        raise FileNotFoundError(f"--rerun: no Rerun viewer could be started ({str(exc).strip().splitlines()[0]}); "
                                "give a file instead, --rerun job.rrd") from None


def _template_points(t, method: str) -> dict[str, np.ndarray]:
    """A template method's query points per stage (M, 3), in their anchor's frame; none for other methods."""
    from app.predict.methods import method as method_record
    from app.tasks.demo_library import task_templates

    m = method_record(method)
    if not m.template:
        return {}
    return {stage: template.points for stage, template in task_templates(t, query=m.query, feature=m.feature).items()}
