"""What happens to the object in the oracle's executed jobs: how far it turns in the grasp by each
stage, how wide the fingers got when letting go, and what the arm touched when it stopped
(docs/jobs.md, "Onto a peg" and "Finger openings").

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_oracle_job.py TASK POSE SEED... [--peg-clearance M]
    [--release-clearance M] [--approach-clearance M] [--calibration FILE]
e.g. `mug upright 5 --peg-clearance 0.006` (~10 s a job). Each job runs alone in a fresh cell, with
the true camera pose (as tests/test_jobs.py does) or the calibration file's (as `nift bench-jobs
--calibration` does); the defaults are the cell's.
"""
import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

import hardware.sim.arm as sim_arm
from app.jobs.job import JobConfig
from app.motion.scene import PlanningScene
from app.simcell.calibration import ensure_calibration
from app.simcell.cell import CellConfig, SimCell
from app.simcell.sim_job import JobSpec, SimHooks, run_sim_job
from app.tasks.task import task
from hardware.bullet import p
from hardware.se3 import invert, rotation_angle, ur_to_pose


class Watch(SimHooks):
    """Records the object's pose in the TCP frame after every stage, and the fingers' width."""

    def keyframe(self, label: str) -> None:
        T_tcp_obj = invert(ur_to_pose(self.cell.arm.getActualTCPPose())) @ self.cell.world.pose(self.obj.body)
        self.poses = {**getattr(self, "poses", {}), label: T_tcp_obj}
        self.widths = {**getattr(self, "widths", {}), label: self.cell.gripper.width}
        fixture = self.cell.fixtures[self.task.fixture]
        on = "on the fixture" if self.cell.world.in_contact(self.obj.body, fixture) else "off the fixture"
        x, y, z = self.cell.world.pose(self.obj.body)[:3, 3]
        self.where = {**getattr(self, "where", {}), label: f"{on}, at ({x:.3f}, {y:.3f}, {z:.3f})"}


def touched_when_stopped(arm: sim_arm.SimArm) -> list[str]:
    """The arm's links in contact with other bodies, with the normal force (N), as it stops."""
    robot = arm.robot
    contacts = p.getContactPoints(bodyA=robot.body, physicsClientId=robot.client)
    links = {index: name for name, index in robot.links.items()}
    def name(body: int) -> str:
        mass = p.getDynamicsInfo(body, -1, physicsClientId=robot.client)[0]
        return f"body{body}" + (f" ({mass:.2f} kg)" if mass else " (static)")
    return sorted({f"{links.get(c[3], c[3])}-{name(c[2])} {c[9]:.0f} N" for c in contacts if c[2] != robot.body and c[9] > 1})


parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("task")
parser.add_argument("pose")
parser.add_argument("seeds", nargs="+", type=int)
parser.add_argument("--method", default="teacher", help="teacher (the oracle) or a method of `nift run`")
parser.add_argument("--peg-clearance", type=float, default=None)
parser.add_argument("--release-clearance", type=float, default=None)
parser.add_argument("--approach-clearance", type=float, default=None)
parser.add_argument("--calibration", type=Path, default=None, help="camera calibration file (calibrated first if missing)")
args = parser.parse_args()
job = JobConfig.of(args.method)
if args.peg_clearance is not None:
    job = replace(job, motion=replace(job.motion, peg_clearance=args.peg_clearance))
for name in ("release_clearance", "approach_clearance"):
    if getattr(args, name) is not None:
        job = replace(job, **{name: getattr(args, name)})

stops: list[str] = []
watches: list[Watch] = []


def watching(*hook_args) -> Watch:
    watches.append(Watch(*hook_args))
    return watches[-1]


for seed in args.seeds:
    config, stops[:] = CellConfig(), []
    with SimCell(config) as cell:
        cell.arm.on_stop.append(lambda reason, arm=cell.arm: stops.append(", ".join(touched_when_stopped(arm))))
        scene = PlanningScene(config)
        T_cam = np.array(cell.camera.config.T_base_cam) if args.calibration is None else ensure_calibration(cell, args.calibration)
        try:
            result = run_sim_job(cell, scene, T_cam, JobSpec(task(args.task), seed, args.pose),
                                 job, hooks_type=watching)
        finally:
            scene.close()
    w = watches[-1]
    grasp = w.poses.get("grasp")
    turns = {k: np.degrees(rotation_angle((invert(grasp) @ w.poses[k])[:3, :3])) for k in ("lift", "carry", "place")
             if grasp is not None and k in w.poses}
    print(f"{args.task} {args.pose} {seed}: {'ok' if result.success else result.failed_stage + ': ' + result.reason}")
    print("  turned in the grasp (deg): " + "  ".join(f"{k} {v:.1f}" for k, v in turns.items()))
    if "release" in w.widths:
        print(f"  fingers after letting go: {1000 * w.widths['release']:.1f} mm")
    print("  the object after each stage: " + "; ".join(f"{k}: {v}" for k, v in w.where.items()
                                                          if k in ("place", "release", "retreat", "verify") or "failed" in k))
    if stops:
        print(f"  touching when the arm stopped: {stops[0] or 'nothing'}")
    if result.notes:
        print("  notes: " + "; ".join(result.notes))
