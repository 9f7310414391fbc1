"""The benchmark protocol (docs/benchmark.md, after NDF): which objects, poses and clouds each trial gets.

A trial is (task, pose setting, index). Its seed fixes the unseen test-split instance, the
uniform random scale, the pose (upright: random yaw and place on the table; arbitrary: Haar
random rotation, held in mid-air while observed) and the camera noise, so every method in a run
sees the same object in the same pose through the same cloud. Clouds are ray cast from the
object's mesh at its simulated pose with the Kinect's noise model (the generator `nift make-data`
uses): `single` from the cell's camera, `fused` from four cameras at the corners of the table
around the object (the paper's simulated setting), resampled to 1,024 points.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from app.nift.field import FUSED_FIELDS
from app.nift.imitation_config import ImitationConfig
from app.nift.raycast import scene_of
from app.predict.config import PredictConfig
from app.predict.methods import method as method_record
from app.perception import resample
from app.simcell.cell import CellConfig
from app.training.views import CAMERAS, kinect_cloud
from hardware.sim.kinect import look_at

SETTINGS = ("teleported", "executed")
CLOUD_POINTS = 1024
FUSED_DISTANCE = 1.0  # m from the object's centre
FUSED_ELEVATION_DEG = 35.0


@dataclass(frozen=True)
class BenchConfig:
    """One benchmark run: what is compared on which trials."""

    tasks: tuple[str, ...] = ("mug", "bowl", "bottle")
    poses: tuple[str, ...] = ("upright", "arbitrary")
    methods: tuple[str, ...] = ("cpd", "bps-ndf", "bps-scf", "bps-nif", "ibs-ndf", "ibs-scf", "ibs-nif")
    trials: int = 100
    demos: int = 10
    camera: str = "single"
    setting: str = "teleported"
    seed: int = 0
    nif: str | None = None  # other field weights (app.nift.template.field_override): a NIF .pt or a dir of nif.pt + ndf.pt
    center_grasp: bool = True  # centre every method's grasp between the fingers and hang on the peg (app.predict.grasp_centering, app.predict.peg_centering)
    align_grasp: bool | None = None  # turn every method's grasp square to the wall between the fingers (app.predict.grasp_alignment); None: `aligns`
    feasible: bool = True  # rank template methods' candidate poses by feasibility first (app.predict.feasibility)
    place_contact_scale: float = ImitationConfig.place_contact_scale  # contact weighting of place templates; 0: the paper's
    place_demo_match: str = ImitationConfig.place_demo_match  # place poses against the demos' mean features or the nearest demo's
    objects: tuple[str, ...] = ()  # imported objects (app.objects.library) instead of procedural ones: a task's trials cycle over those of its category
    demo_dir: str | None = None  # the directory whose <task>/ folders hold the demos (default: the project's demos/)
    cell: CellConfig = field(default_factory=CellConfig)

    def objects_for(self, category: str) -> tuple[str, ...]:
        """The named imported objects a task of `category` cycles over (none: procedural objects)."""
        return tuple(n for n in self.objects if imported_category(n) == category)

    def imitation(self, index: int) -> ImitationConfig:
        """The optimiser settings of trial `index` (its seed is the index, as for every method)."""
        return ImitationConfig(seed=index, place_contact_scale=self.place_contact_scale, place_demo_match=self.place_demo_match)

    def predict_config(self, method: str, index: int, demos: Path) -> PredictConfig:
        """What a method's row predicts with in trial `index`: the protocol's schedule and the run's
        refinements; executed jobs also pair the demos' carried grasps, as the cell does."""
        return PredictConfig(method=method, demos=demos, fields=self.fields, imitation=self.imitation(index),
                             center=self.center_grasp, align=self.aligns, feasible=self.feasible,
                             carried_grasps=self.setting == "executed")

    @property
    def fields(self) -> str | None:
        """The field weights the template rows use (`nif`; unset, the fused fields with fused cameras,
        else None: the shipped ones)."""
        if self.nif is None and self.camera == "fused":
            return str(FUSED_FIELDS)  # fields trained on what this setting sees (docs/benchmark.md)
        return self.nif

    @property
    def aligns(self) -> bool:
        """Whether grasps are turned square to the wall between the fingers (`align_grasp`; unset, with
        fused cameras only: one Kinect's normals at a rim are off the mesh's by a median 2-10 degrees, docs/additions.md)."""
        return self.camera == "fused" if self.align_grasp is None else self.align_grasp

    def check(self) -> None:
        """A one-line error for a setting this benchmark does not know."""
        if self.camera not in CAMERAS:
            raise ValueError(f"unknown camera setting {self.camera!r}; choose one of {', '.join(CAMERAS)}")
        if self.setting not in SETTINGS:
            raise ValueError(f"unknown setting {self.setting!r}; choose one of {', '.join(SETTINGS)}")
        if self.trials < 1 or not 1 <= self.demos <= 10:
            raise ValueError(f"--trials must be >= 1 and --demos 1..10 (got {self.trials}, {self.demos})")
        self.imitation(0)  # a bad --place-contact-scale fails here, in one line, not in the workers
        if self.camera != "single" and self.setting == "executed":
            raise ValueError("--setting executed runs the cell, which has one Kinect: use --camera single")
        if self.nif is not None and self.setting == "executed":
            raise ValueError("--fields applies to the teleported setting only (jobs use the shipped fields)")
        if self.objects:
            from app.tasks.task import task

            for name in self.tasks:
                t = task(name)
                if not self.objects_for(t.category):
                    raise ValueError(f"--objects names no {t.category} for the {name} task; "
                                     f"name one or leave the task out of --tasks")
            if any(method_record(m).true_poses for m in self.methods):
                raise ValueError("the oracle needs procedural objects' landmarks; leave it out with --objects")
        if self.demo_dir is not None and not Path(self.demo_dir).is_dir():
            raise ValueError(f"--demo-dir {self.demo_dir}: no such directory")


def imported_category(name: str) -> str:
    """The category of a library object (a one-line error if there is none of that name)."""
    from app.objects.library import object_info

    return object_info(name)["category"]


@dataclass(frozen=True)
class Trial:
    """One object in one pose, seen once, judged for every method."""

    task: str
    pose: str
    index: int

    @property
    def key(self) -> str:
        return f"{self.task}/{self.pose}/{self.index}"

    def seed(self, run_seed: int) -> list[int]:
        """The trial's seed sequence: stable under a change of the other trials or the methods."""
        return [run_seed, sum(map(ord, self.task)), sum(map(ord, self.pose)), self.index]


def trials(config: BenchConfig) -> list[Trial]:
    """Every trial of a run, index-major: a run stopped early has about as many trials in every cell."""
    return [Trial(t, p, i) for i in range(config.trials) for t in config.tasks for p in config.poses]


def parse_indices(specs: list[str]) -> list[int]:
    """Trial indices from command-line specs: '3' -> [3]; '0-25' -> 0..24."""
    out = []
    for spec in specs:
        a, _, b = spec.partition("-")
        out.extend(range(int(a), int(b)) if b else [int(a)])
    return out


def camera_eyes(camera: str, center: np.ndarray, cell: CellConfig) -> list[np.ndarray]:
    """Eye positions (base frame) of the camera setting looking at `center`."""
    if camera == "single":
        return [np.asarray(cell.camera_eye, float)]
    el = np.radians(FUSED_ELEVATION_DEG)
    return [center + FUSED_DISTANCE * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
            for az in np.radians(45.0) + np.arange(4) * np.pi / 2]


def trial_cloud(mesh: trimesh.Trimesh, T_base_obj: np.ndarray, camera: str, rng: np.random.Generator,
                cell: CellConfig = CellConfig()) -> np.ndarray:
    """The object's cloud (1024, 3) in the base frame as the camera setting sees it."""
    posed = mesh.copy().apply_transform(T_base_obj)
    center = posed.bounds.mean(axis=0)
    radius = float(np.linalg.norm(posed.vertices - center, axis=1).max())
    scene = scene_of(posed)
    target = np.asarray(cell.camera_target, float) if camera == "single" else center
    clouds = [kinect_cloud(scene, look_at(eye, target), rng, sphere=(center, radius))
              for eye in camera_eyes(camera, center, cell)]
    cloud = np.concatenate(clouds)
    if len(cloud) < 32:
        raise ValueError(f"the camera saw only {len(cloud)} points of the object")
    return resample(cloud, CLOUD_POINTS, int(rng.integers(2**31)))
