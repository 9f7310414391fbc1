"""Teach-in: record verified demos of a task in the sim cell and build the task's templates.

One demo: an upright object of the task's category (train split) is spawned; the camera captures
it and perception cuts out its cloud (with the calibrated camera pose); the operator's grasp
(T_obj_tcp) and place (T_fixture_obj) - from a file, or the scripted teacher's - are checked with
the success judges; only a demo whose grasp and place both succeed is kept. The templates
(grasp: gripper anchor; place: rack / shelf anchor) are then rebuilt from all the task's demos.

Layout of a task's directory (`demos/<task>/`): demo-NN.npz (nift-demo/1), and
{grasp,place}-<query>-<feature>.nit.npz (nift-nit/1) - the shipped ones are ibs-nif, NIFT's own.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Callable

import numpy as np

from app.anchors import anchor_mesh
from app.cell import SimCell
from app.demo import Demo, load_demo, save_demo
from app.judges import judge_grasp, judge_place
from app.nift.template import (StaleTemplate, Template, build_template, field_id, load_template, field_override,
                               save_template, with_demo_features)
from app.objects import split
from app.perception import object_cloud
from app.spawn import spawn
from app.tasks import Task, teacher_grasp, teacher_place

DEMOS_DIR = Path(__file__).resolve().parent.parent / "demos"
STAGES = ("grasp", "place")


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
    K = cell.camera.intrinsics
    demo = Demo(t.name, cloud, T_base_obj, T_base_obj @ T_obj_tcp, T_fixture_obj, T_base_fixture, T_base_cam,
                {k: getattr(K, k) for k in ("width", "height", "fx", "fy", "cx", "cy")}, t.category, seed,
                obj.scale, name, {"grasp": grasp.reason, "place": place.reason})
    return demo, "kept"


def record_task(cell: SimCell, t: Task, count: int, out: Path, T_base_cam: np.ndarray, seed: int = 0,
                report: Callable[[str], None] = print) -> list[Path]:
    """Record `count` verified demos with the scripted teacher into out/demo-NN.npz."""
    rng = np.random.default_rng(seed)
    candidates = rng.permutation(split(t.category, "train"))
    paths: list[Path] = []
    for instance in candidates:
        if len(paths) == count:
            break
        name = f"demo-{len(paths):02d}"
        demo, why = record_demo(cell, t, int(instance), T_base_cam, rng, name=name)
        report(f"{t.name} instance {instance}: {why}")
        if demo is not None:
            paths.append(save_demo(demo, out / f"{name}.npz"))
    if len(paths) < count:
        raise ValueError(f"only {len(paths)} of {count} demos passed the judges")
    return paths


def task_demos(out: Path) -> list[Demo]:
    """Every demo in a task directory, in name order."""
    paths = sorted(out.glob("demo-*.npz"))
    if not paths:
        raise FileNotFoundError(f"no demos in {out}: record some with `nift teach`")
    return [load_demo(p) for p in paths]


def template_path(out: Path, stage: str, query: str = "ibs", feature: str = "nif", nif: str | Path | None = None) -> Path:
    """Where a task's template lives; templates built with other field weights than the shipped ones
    (`nif`: see `field_override`) carry the weights' hash in the name, so several sit side by side."""
    weights = field_override(feature, nif)
    tag = "" if weights is None else f".{field_id(weights).split(':')[1]}"
    return out / f"{stage}-{query}-{feature}{tag}.nit.npz"


def build_task_templates(t: Task, demos: list[Demo], query: str = "ibs", feature: str = "nif",
                         n_points: int = 500, seed: int = 0, nif: str | Path | None = None) -> dict[str, Template]:
    """The grasp and place templates of a task from its demos (`nif`: NIF weights, default shipped)."""
    weights = field_override(feature, nif)
    return {stage: build_template(stage_anchor(t, stage), anchor_mesh(stage_anchor(t, stage)), template_frames(demos, stage),
                                  query, feature, n_points, weights=weights, seed=seed) for stage in STAGES}


def stage_anchor(t: Task, stage: str) -> str:
    """The anchor of a stage's template: the gripper for the grasp, the task's fixture for the place."""
    return "gripper" if stage == "grasp" else t.fixture


def template_frames(demos: list[Demo], stage: str) -> list[dict]:
    """The demos as `build_template` takes them for a stage: cloud, name and the anchor's pose."""
    return [{"cloud": d.cloud, "name": d.name,
             "T_frame_anchor": d.grasp_anchor() if stage == "grasp" else d.place_anchor()} for d in demos]


@lru_cache(maxsize=8)
def _with_demo_features(path: Path, stamp: int, directory: Path, stage: str, weights: str | Path | None) -> Template:
    """A saved template with its demos' own features, once per process and file version (`stamp`):
    they take one encoding per demo (~0.2 s each on a CPU) and are not saved."""
    return with_demo_features(load_template(path, weights), template_frames(task_demos(directory), stage), weights)


def task_templates(t: Task, directory: Path | None = None, query: str = "ibs", feature: str = "nif",
                   rebuild: bool = False, nif: str | Path | None = None,
                   per_demo: tuple[str, ...] = ()) -> dict[str, Template]:
    """A task's templates from its directory, built from the demos (and saved) when missing, built
    with other field weights, or asked; those of the stages `per_demo` with each demo's own features
    (`Template.per_demo`)."""
    directory = directory or DEMOS_DIR / t.demos
    weights = field_override(feature, nif)
    paths = {s: template_path(directory, s, query, feature, nif) for s in STAGES}
    if not rebuild and all(p.is_file() for p in paths.values()):
        try:
            templates = {s: load_template(p, weights) for s, p in paths.items()}
        except StaleTemplate:  # the weights changed since: the demos are the source, rebuild
            pass
        else:
            for s in per_demo:
                templates[s] = _with_demo_features(paths[s], paths[s].stat().st_mtime_ns, directory, s, weights)
            return templates
    templates = build_task_templates(t, task_demos(directory), query, feature, nif=nif)
    for stage, template in templates.items():
        save_template(template, paths[stage])
    return templates
