"""One benchmark trial: an object in a pose, seen once, and every method's verdicts on it.

Teleported (the paper's setting): each method's grasp is judged by a free-floating gripper at the
predicted pose, its place by setting the object at the predicted goal pose, each on a freshly
spawned copy of the object in the trial's pose; beside that judge, each teleported row says whether
the open gripper at the grasp would reach into the table (`gripper_in_table`: its lowest corner
more than 2 mm below the top), which the paper's protocol ignores and a cell cannot do. Executed:
the whole job runs in the sim cell (camera, perception, IK, trajectories, the gripper) for each method.
"""
from __future__ import annotations

import time

import numpy as np

from app.bench.protocol import BenchConfig, Trial, trial_cloud
from app.failures import INTERNAL_ERROR
from app.jobs.job import JobConfig
from app.motion.scene import PlanningScene
from app.objects.library import LibraryObject, load_object
from app.predict.methods import method as method_record
from app.predict.predict import predict
from app.simcell.cell import CellConfig, SimCell, add_fixtures
from app.simcell.sim_job import JobSpec, run_sim_job, spawn_test_object
from app.simcell.judges import judge_grasp, judge_place, judged_copy
from app.simcell.oracle import oracle_prediction
from app.simcell.spawn import SpawnedObject
from app.tasks.task import task
from hardware.gripper_geometry import lowest_point
from hardware.sim.world import SimWorld, SimWorldConfig

IN_TABLE = 0.002  # m below the table top that count as into the table


class ImportedObjects:
    """The imported objects of a run, loaded once per worker: trial i of a task takes the i-th of its
    category's, cyclically (none named: procedural objects)."""

    def __init__(self, names: tuple[str, ...]) -> None:
        self.objects = [load_object(n) for n in names]

    def source(self, trial: Trial) -> LibraryObject | None:
        own = [o for o in self.objects if o.category == task(trial.task).category]
        return own[trial.index % len(own)] if own else None


class TeleportedBench:
    """A physics world with the fixtures, reused for every trial of a worker."""

    def __init__(self, cell: CellConfig, objects: tuple[str, ...] = ()) -> None:
        self.cell = cell
        self.source = ImportedObjects(objects).source
        self.world = SimWorld(SimWorldConfig())
        self.world.connect()
        self.fixtures = add_fixtures(self.world, cell)

    def close(self) -> None:
        self.world.disconnect()

    def observe(self, trial: Trial, camera: str, seed: int) -> tuple[SpawnedObject, np.ndarray, np.ndarray]:
        """The trial's object (removed again from the world), its pose T_base_obj and the cloud
        (1024, 3) the camera setting sees - drawn from the trial's seed, the same for every method."""
        rng = np.random.default_rng(trial.seed(seed))
        obj = spawn_test_object(self.world, task(trial.task), trial.pose, rng, self.source(trial))
        T_base_obj = self.world.pose(obj.body)
        self.world.remove(obj.body)
        return obj, T_base_obj, trial_cloud(obj.mesh, T_base_obj, camera, rng, self.cell)

    def run(self, trial: Trial, config: BenchConfig, demo_root) -> list[dict]:
        """Rows (one per method) for a trial."""
        t = task(trial.task)
        obj, T_base_obj, cloud = self.observe(trial, config.camera, config.seed)
        T_base_fixture = self.cell.fixture_pose(t.fixture)
        base = {"trial": trial.key, "task": t.name, "pose": trial.pose, "index": trial.index, "instance": obj.seed,
                "scale": round(obj.scale, 4), **({"object": obj.source.name} if obj.source else {})}
        rows = []
        for method in config.methods:
            start = time.perf_counter()
            try:
                if method_record(method).true_poses:
                    pred = oracle_prediction(t, obj.mesh, obj.scale, T_base_obj, T_base_fixture)
                else:
                    pred = predict(t, cloud, config.predict_config(method, trial.index, demo_root / t.demos),
                                   T_base_fixture)
            except ValueError as exc:
                rows.append({**base, "method": method, "grasp": False, "place": False, "overall": False,
                             "gripper_in_table": False, "why": f"no prediction: {exc}", "seconds": round(time.perf_counter() - start, 2)})
                continue
            seconds = time.perf_counter() - start
            grasp = judged_copy(self.world, obj, T_base_obj, lambda o: judge_grasp(self.world, o, pred.T_base_tcp),
                                trial.pose)
            place = judged_copy(self.world, obj, T_base_obj,
                                lambda o: judge_place(self.world, o, pred.motion @ T_base_obj,
                                                      self.fixtures[t.fixture], t.upright), trial.pose)
            rows.append({**base, "method": method, "grasp": grasp.success, "place": place.success,
                         "overall": grasp.success and place.success,
                         "gripper_in_table": lowest_point(pred.T_base_tcp) < -IN_TABLE,
                         "why": f"grasp: {grasp.reason}; place: {place.reason}", "seconds": round(seconds, 2)})
        return rows


class ExecutedBench:
    """The sim cell with its planning scene, reused for every trial of a worker."""

    def __init__(self, cell: CellConfig, objects: tuple[str, ...] = ()) -> None:
        self.source = ImportedObjects(objects).source
        self.sim = SimCell(cell)
        self.sim.connect()
        self.scene = PlanningScene(cell)
        self.T_base_cam = np.array(self.sim.camera.config.T_base_cam)  # calibration is measured on its own

    def close(self) -> None:
        self.scene.close()
        self.sim.disconnect()

    def run(self, trial: Trial, config: BenchConfig, demo_root) -> list[dict]:
        t = task(trial.task)
        rows = []
        for method in config.methods:
            job = JobConfig(predict=config.predict_config(method, trial.index, demo_root / t.demos))
            spec = JobSpec(t, tuple(trial.seed(config.seed)), trial.pose, self.source(trial))
            r = run_sim_job(self.sim, self.scene, self.T_base_cam, spec, job)
            failed = r.failed_stage or ""
            grasp = r.success or failed in ("place", "release", "retreat", "verify")  # held through the carry
            rows.append({"trial": trial.key, "task": t.name, "pose": trial.pose, "index": trial.index,
                         "instance": r.info["instance"], "scale": r.info["scale"], "method": method, "grasp": grasp,
                         "place": r.success, "overall": r.success,
                         "why": r.reason if r.success else f"failed at {failed}: {r.reason}",
                         "seconds": round(sum(r.seconds.values()), 2),
                         **({"internal_error": True} if r.failure_kind == INTERNAL_ERROR else {})})
        return rows
