"""Jobs in the simulated cell: an unseen test-split object spawned per job, the simulator's
hooks (release an arbitrary-pose object once the fingers close, check where it came to rest,
key-frame pictures), and series of jobs.

Between jobs the simulated operator clears the cell: the object is removed and, if a failed job
left the arm elsewhere, it is put back home and any protective stop is unlocked.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from app.io_utils import numbered
from app.jobs.job import JobConfig, JobHooks, JobResult, Predictor, run_job
from app.jobs.log import JobLog
from app.motion.scene import PlanningScene
from app.objects import split
from app.objects.library import LibraryObject
from app.predict.methods import method as method_record
from app.simcell.cell import SimCell
from app.simcell.judges import resting_verdict
from app.simcell.oracle import REVOLUTION, TURNS, oracle_prediction
from app.simcell.sampling import sampled
from app.simcell.snapshots import save_strip, snapshot
from app.simcell.spawn import SCALE_RANGE, SpawnedObject, release, spawn
from app.tasks.task import Task
from hardware.sim.world import SimWorld

SETTLE_TIME = 1.0  # s the object is left to come to rest before the verdict


@dataclass(frozen=True)
class JobSpec:
    """Which object a simulated job gets: the task, the pose setting, and the seed that picks the
    test-split instance, its scale and its pose; or an imported object (at its own size), whose pose
    the seed picks."""

    task: Task
    seed: int | tuple[int, ...]
    pose: str = "upright"
    source: LibraryObject | None = None
    split: str = "test"  # the procedural objects' split (app.objects.families)


class SimHooks(JobHooks):
    """The simulator's side of a job."""

    def __init__(self, cell: SimCell, obj: SpawnedObject, t: Task, record: bool = False) -> None:
        self.cell, self.obj, self.task, self.record = cell, obj, t, record
        self.frames: list[np.ndarray] = []

    def on_grasped(self) -> None:
        release(self.cell.world, self.obj)  # an arbitrary-pose object was held in mid-air until now

    def keyframe(self, label: str) -> None:
        if self.record:
            self.frames.append(snapshot(self.cell.world, label))

    def verify(self, seen: tuple[bool, str]) -> tuple[bool, str]:
        """The simulator's ground truth (the benchmark's judge); the job's camera check is in the record."""
        world = self.cell.world
        world.step(int(SETTLE_TIME / world.config.time_step))
        verdict = resting_verdict(world, self.obj, self.cell.fixtures[self.task.fixture], self.task.upright)
        return verdict.success, verdict.reason


def spawn_test_object(world: SimWorld, t: Task, pose: str, rng: np.random.Generator,
                      source: LibraryObject | None = None, part: str = "test") -> SpawnedObject:
    """An unseen object: an instance of split `part`, uniform scale and the pose setting's pose, all from
    rng; or the imported `source` at scale 1 in a pose from rng."""
    instance = int(rng.choice(split(t.category, part)))
    scale = float(rng.uniform(*SCALE_RANGE))  # drawn for imported objects too: the pose is the same draw either way
    if source is not None:
        return spawn(world, t.category, instance, pose, rng=rng, source=source)
    return spawn(world, t.category, instance, pose, scale=scale, rng=rng)


def reset_arm(cell: SimCell) -> None:
    """Put the arm home and open the gripper (the simulated operator's reset between jobs)."""
    home = np.asarray(cell.config.arm.home_q)
    if cell.arm.isProtectiveStopped():
        cell.arm.unlockProtectiveStop()
    if np.abs(cell.arm.getActualQ() - home).max() > 1e-3:
        cell.robot.reset_arm(home)
    cell.gripper.open()


def start_job(cell: SimCell, spec: JobSpec) -> SpawnedObject:
    """The operator's reset, the camera reseeded by the job's seed (its frames follow from the seed
    alone) and the spec's object spawned."""
    reset_arm(cell)
    cell.camera.reseed(np.random.SeedSequence(spec.seed).spawn(1)[0])
    return spawn_test_object(cell.world, spec.task, spec.pose, np.random.default_rng(spec.seed), spec.source, spec.split)


def oracle_predictor(cell: SimCell, obj: SpawnedObject, t: Task) -> Predictor:
    """The oracle's poses for the object where it is when the job asks (after a miss it may have moved);
    for a body of revolution, its grasp turned about the object's axis too (`app.simcell.oracle`)."""
    T_base_fixture = cell.config.fixture_pose(t.fixture)
    turns = TURNS if t.category in REVOLUTION else 1
    return lambda cloud: oracle_prediction(t, obj.mesh, obj.scale, cell.world.pose(obj.body), T_base_fixture, turns)


def run_sim_job(cell: SimCell, scene: PlanningScene, T_base_cam: np.ndarray, spec: JobSpec,
                config: JobConfig = JobConfig(), record: Path | None = None, hooks_type: type[SimHooks] = SimHooks,
                predictor_of: Callable[[SpawnedObject], Predictor] | None = None,
                job_log: JobLog | None = None) -> JobResult:
    """Spawn the spec's object, run the job, remove the object; the strip goes to `record`, what the job
    saw and did to `job_log`, with the controller's state sampled from the physics loop
    (`hooks_type`, `predictor_of(object)`: other simulator hooks and poses, for tests)."""
    job_log = job_log or JobLog()
    obj = start_job(cell, spec)
    hooks = hooks_type(cell, obj, spec.task, record is not None)
    try:
        hooks.keyframe("start")
        T_base_fixture = cell.config.fixture_pose(spec.task.fixture)
        predictor = None
        if predictor_of is not None:
            predictor = predictor_of(obj)
        elif method_record(config.method).true_poses:
            predictor = oracle_predictor(cell, obj, spec.task)
        with sampled(cell, job_log):
            result = run_job(spec.task, cell.arm, cell.gripper, cell.camera, T_base_cam, T_base_fixture, scene, config,
                             hooks, predictor, job_log=job_log)
        if not result.success:
            hooks.keyframe(f"failed at {result.failed_stage}")
    finally:
        cell.world.remove(obj.body)
    result.info = {"seed": spec.seed, "pose": spec.pose, "instance": obj.seed, "scale": round(obj.scale, 4)}
    if obj.source is not None:
        result.info["object"] = obj.source.name
    if record is not None:
        result.info["record"] = str(save_strip(hooks.frames, record))
    return result


REFRESH_EVERY = 20  # jobs between fresh physics clients in a series (memory: docs/limits.md, "Soak")


def fresh_client_before(i: int, every: int = REFRESH_EVERY) -> bool:
    """Whether a series (`run_series`) starts the cell and the scene on fresh clients before its job i."""
    return bool(i and every and i % every == 0)


def run_series(cell: SimCell, scene: PlanningScene, T_base_cam: np.ndarray, specs: list[JobSpec],
               config: JobConfig = JobConfig(), on_result: Callable[[JobResult], None] = lambda r: None,
               record: Path | None = None, refresh_every: int = REFRESH_EVERY,
               job_log: Callable[[int], JobLog | None] = lambda i: None) -> list[JobResult]:
    """Run jobs one after the other; `record` (a .png) gets one strip per job, numbered if several, and
    `job_log(i)` the log of job i;
    every `refresh_every` jobs the cell and the planning scene start from fresh PyBullet clients,
    which is what frees the shapes of the objects spawned so far."""
    results = []
    for i, spec in enumerate(specs):
        if fresh_client_before(i, refresh_every):
            cell.refresh()
            scene.rebuild()
        results.append(run_sim_job(cell, scene, T_base_cam, spec, config, numbered(record, i, len(specs)),
                                   job_log=job_log(i)))
        on_result(results[-1])
    return results
