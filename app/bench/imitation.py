"""`nift bench-imitation`: seconds per prediction and pose error against the scripted teacher.

Targets are unseen test-split objects, upright at a random yaw and place in the workspace, with
uniform random scale, seen by the cell's Kinect (ray cast with its noise model, resampled to
1,024 points like perception - no PyBullet, so the benchmark measures the method alone).

Errors respect each task's symmetries: bowls and bottles are bodies of revolution, so the
teacher's grasp is first turned about the object's axis to the predicted grasp's azimuth, and
the two-finger gripper is symmetric under a half turn about its approach axis. On the shelf any
yaw and any spot on the board is as good as another, so the place error there is the object's
height error and its tilt; on the rack it is the full pose error.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
import torch

from app.fanout.cluster import ClusterConfig
from app.fanout.run import fan_out
from app.nift.imitate import ImitationConfig
from app.nift.raycast import scene_of
from app.objects import split
from app.perception import resample
from app.predict.config import PredictConfig
from app.predict.predict import predict
from app.simcell.cell import WORKSPACE, CellConfig
from app.simcell.spawn import SCALE_RANGE
from app.tasks.task import task, teacher_grasp, teacher_place
from app.training.views import kinect_cloud
from hardware.se3 import invert, make_pose, pose_error, rotvec_to_matrix
from hardware.sim.kinect import look_at

HALF_TURN = make_pose(rotvec_to_matrix([0.0, 0.0, np.pi]))


def target(category: str, seed: int, rng: np.random.Generator, cell: CellConfig = CellConfig()):
    """(mesh scaled, T_base_obj, cloud (1024, 3) base frame) of an upright test object."""
    from app.objects import generate

    mesh = generate(category, seed)
    scale = rng.uniform(*SCALE_RANGE)
    mesh.apply_scale(scale)
    (x0, x1), (y0, y1) = WORKSPACE
    T_base_obj = make_pose(rotvec_to_matrix([0, 0, rng.uniform(-np.pi, np.pi)]), [rng.uniform(x0, x1), rng.uniform(y0, y1), 0])
    posed = mesh.copy().apply_transform(T_base_obj)
    center = posed.bounds.mean(axis=0)
    radius = float(np.linalg.norm(posed.vertices - center, axis=1).max())
    T_base_cam = look_at(cell.camera_eye, cell.camera_target)
    cloud = kinect_cloud(scene_of(posed), T_base_cam, rng, sphere=(center, radius))
    return mesh, T_base_obj, resample(cloud, 1024, int(rng.integers(2**31))), scale


def grasp_error(category: str, T_base_obj: np.ndarray, T_pred: np.ndarray, T_teacher: np.ndarray) -> tuple[float, float]:
    """(metres, degrees) between predicted and teacher grasp, modulo the task's symmetries."""
    T_obj_pred, T_obj_teacher = invert(T_base_obj) @ T_pred, invert(T_base_obj) @ T_teacher
    if category in ("bowl", "bottle"):
        turn = np.arctan2(T_obj_pred[1, 3], T_obj_pred[0, 3]) - np.arctan2(T_obj_teacher[1, 3], T_obj_teacher[0, 3])
        T_obj_teacher = make_pose(rotvec_to_matrix([0, 0, turn])) @ T_obj_teacher
    errs = [pose_error(T_obj_pred, T_obj_teacher @ flip) for flip in (np.eye(4), HALF_TURN)]
    dist, angle = min(errs, key=lambda e: e[1])
    return dist, float(np.degrees(angle))


def place_error(fixture: str, goal_pred: np.ndarray, goal_teacher: np.ndarray) -> tuple[float, float]:
    """(metres, degrees): full pose error on the rack; height error and tilt on the shelf."""
    if fixture == "rack":
        dist, angle = pose_error(goal_pred, goal_teacher)
        return dist, float(np.degrees(angle))
    tilt = np.degrees(np.arccos(np.clip(goal_pred[2, 2], -1.0, 1.0)))
    return abs(goal_pred[2, 3] - goal_teacher[2, 3]), float(tilt)


def schedule_settings(schedule: str, method: str, seed: int, config: ImitationConfig) -> PredictConfig:
    """What a prediction does: "teleported", the paper tables' (`config`, no centring, no carried
    grasps); "cell", a job's (`PredictConfig`'s defaults: the cell's schedule and every refinement)."""
    if schedule == "cell":
        cell = PredictConfig(method=method)
        return replace(cell, imitation=replace(cell.imitation, seed=seed))
    return PredictConfig(method=method, imitation=replace(config, seed=seed), center=False, carried_grasps=False)


@dataclass(frozen=True)
class Case:
    """One prediction to measure: a test object of a task, drawn from its own seed (whatever runs it)."""

    task: str
    object_seed: int
    draw: tuple[int, ...]  # the random draws' seed: scale, pose, camera noise, resampling


@dataclass(frozen=True)
class Measured:
    """A prediction's wall seconds, grasp and place errors (m, deg), iterations, seconds per template."""

    row: tuple[float, ...]
    per_template: tuple[float, ...]


def cases(tasks: tuple[str, ...], n: int, seed: int) -> list[Case]:
    """`n` unseen test objects per task, each with seeds of its own."""
    out = []
    for name in tasks:
        picks = np.random.default_rng([seed, len(name)]).choice(split(task(name).category, "test"), size=n,
                                                                 replace=False)
        out += [Case(name, int(s), (seed, len(name), k)) for k, s in enumerate(picks)]
    return out


def measure(settings: PredictConfig, case: Case) -> Measured:
    """Time one whole `predict` on the case's object and score it against the teacher."""
    cell, t = CellConfig(), task(case.task)
    mesh, T_base_obj, cloud, scale = target(t.category, case.object_seed, np.random.default_rng(case.draw), cell)
    T_base_fixture = cell.fixture_pose(t.fixture)
    start = time.perf_counter()
    pred = predict(t, cloud, settings, T_base_fixture)
    wall = time.perf_counter() - start
    g = grasp_error(t.category, T_base_obj, pred.T_base_tcp, T_base_obj @ teacher_grasp(mesh))
    goal = T_base_fixture @ teacher_place(t, mesh, scale)
    p = place_error(t.fixture, pred.motion @ T_base_obj, goal)
    return Measured((wall, *g, *p, *pred.iterations.values()), tuple(pred.seconds.values()))


def _settings(payload: tuple[PredictConfig, int]) -> PredictConfig:
    """A worker's state: the settings, on the schedule's torch threads (a job's for "cell")."""
    from app.nift.imitate import use_threads

    settings, threads = payload
    use_threads(threads)
    return settings


def _figures(name: str, measured: list[Measured]) -> dict:
    """A task's medians: seconds per prediction and per template, errors, iterations."""
    a = np.array([m.row for m in measured], dtype=float)
    med = np.median(a, axis=0)
    figures = {
        f"{name}_seconds_per_prediction": round(float(med[0]), 2),  # the whole predict: grasp, place, refinements
        f"{name}_seconds_per_template": round(float(np.median([s for m in measured for s in m.per_template])), 2),
        f"{name}_grasp_error_mm": round(1000 * float(med[1]), 1),
        f"{name}_grasp_error_deg": round(float(med[2]), 1),
        f"{name}_place_error_mm": round(1000 * float(med[3]), 1),
        f"{name}_place_error_deg": round(float(med[4]), 1),
    }
    if a.shape[1] > 5:
        figures[f"{name}_iterations"] = [int(v) for v in med[5:]]
    return figures


def run_imitation_benchmark(quick: bool = False, seed: int = 0, method: str = "nift", objects: int = 20,
                            tasks: tuple[str, ...] = ("mug", "bowl", "bottle"),
                            config: ImitationConfig = ImitationConfig(), schedule: str = "teleported",
                            cluster: ClusterConfig = ClusterConfig(1)) -> dict:
    """Per task: median wall seconds per prediction (the whole `predict`), iterations, and median
    grasp / place errors, under `schedule` (`schedule_settings`); the predictions fan out on
    `cluster` (one at a time by default, so the seconds are a cell's)."""
    from app.jobs.settings import JobConfig

    settings = schedule_settings(schedule, method, seed, config)
    threads = JobConfig().threads if schedule == "cell" else torch.get_num_threads()
    if not (cluster.local and cluster.workers <= 1):
        threads = 1  # a worker's: one torch thread each (app.fanout)
    config = settings.imitation
    n = 2 if quick else objects
    todo = cases(tasks, n, seed)
    measured: dict[int, Measured] = {}
    errors = []  # a prediction that raised: named with its error, and the others go on
    for outcome in fan_out(measure, todo, _settings, (settings, threads), cluster):
        case = todo[outcome.index]
        if outcome.failed:
            errors.append(f"{case.task} object {case.object_seed}: {outcome.error}")
        else:
            measured[outcome.index] = outcome.value
    figures: dict = {"method": method, "schedule": schedule, "objects_per_task": n, "inits": config.inits,
                     "prune_every": config.prune_every, "explore_points": config.explore_points,
                     "iterations": config.iterations, "patience": config.patience, "threads": threads,
                     "workers": cluster.workers if cluster.local else None}
    for name in tasks:
        done = [measured[i] for i, c in enumerate(todo) if c.task == name and i in measured]
        figures.update(_figures(name, done) if done else {})
        figures[f"{name}_failed"] = n - len(done)
    if errors:
        figures["errors"] = sorted(errors)
    return figures
