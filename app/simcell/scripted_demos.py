"""Teach-in in the simulated cell: record verified demos of a task.

One demo: an upright object of the task's category (train split) is spawned; the camera captures
it and perception cuts out its cloud (with the calibrated camera pose); the operator's grasp
(T_obj_tcp) and place (T_fixture_obj) - from a file, or the scripted teacher's - are checked with
the success judges; only a demo whose grasp and place both succeed is kept. The task's templates
are then rebuilt from all its demos (`app.tasks.demo_library`).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from app.objects import split
from app.perception import object_cloud
from app.simcell.cell import SimCell
from app.simcell.judges import judge_grasp, judge_place
from app.simcell.spawn import spawn
from app.tasks.demo import Demo, intrinsics_record, save_demo
from app.tasks.task import Task, teacher_grasp, teacher_place


@dataclass(frozen=True)
class TaughtPoses:
    """An operator's poses for one demo: T_obj_tcp (grasp) and T_fixture_obj (place); None = teacher."""

    T_obj_tcp: np.ndarray | None = None
    T_fixture_obj: np.ndarray | None = None


def record_demo(cell: SimCell, t: Task, seed: int, T_base_cam: np.ndarray, rng: np.random.Generator,
                poses: TaughtPoses = TaughtPoses(), name: str = "") -> tuple[Demo | None, str]:
    """Spawn, observe, verify; return (the demo, why) - the demo is None when a judge says no."""
    world = cell.world
    obj = spawn(world, t.category, seed, "upright", rng=rng)
    try:
        cloud = object_cloud(cell.camera.capture(), T_base_cam)
        T_base_obj = world.pose(obj.body)
        T_obj_tcp = teacher_grasp(obj.mesh) if poses.T_obj_tcp is None else poses.T_obj_tcp
        T_fixture_obj = teacher_place(t, obj.mesh, obj.scale) if poses.T_fixture_obj is None else poses.T_fixture_obj
        grasp = judge_grasp(world, obj, T_base_obj @ T_obj_tcp, avoid=(cell.robot.body,))
    finally:
        world.remove(obj.body)
    if not grasp.success:
        return None, f"grasp failed: {grasp.reason}"
    obj = spawn(world, t.category, seed, "upright", T_world_obj=T_base_obj)
    T_base_fixture = cell.config.fixture_pose(t.fixture)
    try:
        place = judge_place(world, obj, T_base_fixture @ T_fixture_obj, cell.fixtures[t.fixture], t.upright)
    finally:
        world.remove(obj.body)
    if not place.success:
        return None, f"place failed: {place.reason}"
    demo = Demo(t.name, cloud, T_base_obj, T_base_obj @ T_obj_tcp, T_fixture_obj, T_base_fixture, T_base_cam,
                intrinsics_record(cell.camera.intrinsics), t.category, seed,
                obj.scale, name, {"grasp": grasp.reason, "place": place.reason},
                taught="teacher" if poses.T_obj_tcp is None and poses.T_fixture_obj is None else "file")
    return demo, "kept"


def record_task(cell: SimCell, t: Task, count: int, out: Path, T_base_cam: np.ndarray, seed: int = 0,
                report: Callable[[str], None] = print, first: int = 0) -> list[Path]:
    """Record `count` verified demos with the scripted teacher into out/demo-NN.npz, numbered from `first`."""
    rng = np.random.default_rng(seed)
    candidates = rng.permutation(split(t.category, "train"))
    paths: list[Path] = []
    for instance in candidates:
        if len(paths) == count:
            break
        name = f"demo-{first + len(paths):02d}"
        demo, why = record_demo(cell, t, int(instance), T_base_cam, rng, name=name)
        report(f"{t.name} instance {instance}: {why}")
        if demo is not None:
            paths.append(save_demo(demo, out / f"{name}.npz"))
    if len(paths) < count:
        raise ValueError(f"only {len(paths)} of {count} demos passed the judges")
    return paths
