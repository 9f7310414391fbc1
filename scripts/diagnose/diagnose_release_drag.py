"""What the fingers touch while they let go (docs/jobs.md, "Objects dragged off the shelf on the
release"): runs the oracle's (or a method's) job on a seed and prints, at the place, every 40 steps of the release's
opening and after it, where the object is and each finger contact: its force, its point and its normal
(Bullet's, on the finger, pointing towards the object) in the TCP frame (y: the fingers' axis).

A normal whose y points away from the object (the outer finger's -y contact pointing -y) holds the
object to the pad: it follows the finger as it opens. `--keep-contacts` runs the gripper as it was
before `SimGripper._forget_finger_contacts`, to see that.

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_release_drag.py TASK SEED [--method M] [--keep-contacts]
    [--calibration FILE]       e.g. `bowl 4 --keep-contacts` (~10 s)
"""
import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

from app.jobs.job import JobConfig
from app.motion.scene import PlanningScene
from app.simcell.calibration import ensure_calibration
from app.simcell.cell import CellConfig, SimCell
from app.simcell.sim_job import JobSpec, SimHooks, run_sim_job
from app.tasks.task import task
from hardware.bullet import p
from hardware.se3 import invert, ur_to_pose

PRINT_EVERY = 40  # steps of the opening


class Watch(SimHooks):
    """Prints the object and the finger contacts at the place and after the release; marks the release."""

    releasing = None

    def keyframe(self, label: str) -> None:
        Watch.releasing = self if label == "place" else None
        if label in ("place", "release", "retreat"):
            show(self, label)


def show(hooks: SimHooks, label: str) -> None:
    robot = hooks.cell.robot
    T_tcp = invert(ur_to_pose(hooks.cell.arm.getActualTCPPose()))
    names = {index: name for name, index in robot.links.items()}
    print(f"{label}: object at {np.round(hooks.cell.world.pose(hooks.obj.body)[:3, 3], 4)} m, "
          f"fingers {1000 * hooks.cell.gripper.width:.1f} mm")
    for c in p.getContactPoints(bodyA=hooks.obj.body, bodyB=robot.body, physicsClientId=robot.client):
        if c[9] > 0.2:
            at = (T_tcp @ np.r_[c[5], 1.0])[:3]
            print(f"  {names[c[4]]:13s} {c[9]:5.1f} N at {np.round(1000 * at, 1)} mm, "
                  f"normal {np.round(T_tcp[:3, :3] @ np.array(c[7]), 2)}")


def watched_open(gripper):
    """The gripper's open, printing every PRINT_EVERY steps while the release opens."""
    opening = gripper.open

    def wrapped(speed: float = 0.1, width: float | None = None) -> None:
        hooks = Watch.releasing
        if hooks is None:
            return opening(speed, width)
        world = gripper.robot.world
        step = world.step
        count = [0]

        def counting(n: int = 1) -> None:
            step(n)
            count[0] += 1
            if count[0] % PRINT_EVERY == 0:
                show(hooks, f"opening, step {count[0]}")
        world.step = counting
        try:
            return opening(speed, width)
        finally:
            world.step = step
    return wrapped


parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("task")
parser.add_argument("seed", type=int)
parser.add_argument("--method", default="teacher", help="the method whose poses the job takes (default: the oracle)")
parser.add_argument("--keep-contacts", action="store_true", help="the gripper as before: contacts kept on opening")
parser.add_argument("--calibration", type=Path, default=None, help="camera calibration file (calibrated first if missing)")
args = parser.parse_args()
config = CellConfig()
if args.keep_contacts:
    config = replace(config, gripper=replace(config.gripper, forget_contacts=False))
with SimCell(config) as cell:
    cell.gripper.open = watched_open(cell.gripper)
    scene = PlanningScene(config)
    T_cam = np.array(cell.camera.config.T_base_cam) if args.calibration is None else ensure_calibration(cell, args.calibration)
    try:
        result = run_sim_job(cell, scene, T_cam, JobSpec(task(args.task), args.seed), JobConfig.of(args.method),
                             hooks_type=Watch)
    finally:
        scene.close()
print(f"{args.task} {args.seed}: {'ok' if result.success else result.failed_stage + ': ' + result.reason}")
