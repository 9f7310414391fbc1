"""One job's devices, settings and record, passed between its steps (`app.jobs.job`)."""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable

import numpy as np
import trimesh

from app.jobs.log import JobLog
from app.jobs.motion_meter import MeteredArm
from app.jobs.record import JobHooks, JobResult, stage
from app.jobs.settings import JobConfig, is_hang
from app.layout import fixture_meshes
from app.motion.place_line import above_peg, fixture_approach, peg_line_direction
from app.motion.scene import PlanningScene
from app.predict.pairs import Candidate
from app.predict.hole_places import DemoHang, demo_hang
from app.predict.methods import method as method_record
from app.predict.predict import Prediction
from app.tasks.demo_library import DEMOS_DIR, task_demos
from app.tasks.task import Task
from hardware.interfaces import Arm, DepthCamera, Frame, Gripper
from hardware.kinematics import UR5Kinematics
from hardware.se3 import transform_points

Predictor = Callable[[np.ndarray], Prediction]  # object cloud (N, 3), base frame -> grasp and place
# the held object's cloud as it stood when grasped, the grasp, places to start from -> place candidates
Placer = Callable[[np.ndarray, np.ndarray, np.ndarray], list[Candidate]]


@dataclass
class JobContext:
    """One job's devices, settings and record, passed between its steps."""

    t: Task
    arm: Arm
    gripper: Gripper
    camera: DepthCamera
    T_base_cam: np.ndarray
    T_base_fixture: np.ndarray
    scene: PlanningScene
    kin: UR5Kinematics
    config: JobConfig
    hooks: JobHooks
    predictor: Predictor
    result: JobResult
    placer: Placer | None = None  # imitates the place again after the second look (None: no second look)
    first: Frame | None = None  # the first frame: the fixture without the object
    points: np.ndarray | None = None  # the last look's object points (M, 3) before resampling
    fell: bool = False  # a place missed or a grasp slipped: looks cover the table around the fixture (`JobConfig.fallen_perception`)
    log: JobLog = field(default_factory=JobLog)

    @contextmanager
    def stage(self, name: str):
        """Time stage `name`; a failure in it is recorded as this stage's (`app.jobs.record.stage`); the
        log hears of its start and its end, with the arm's state then; a metered arm counts its motions to it."""
        self.log.stage(name, "started")
        if isinstance(self.arm, MeteredArm):
            self.arm.stage = name
        try:
            with stage(self.result, name, self.hooks):
                yield
        except BaseException:
            self._log_end(name, "failed")
            raise
        self._log_end(name, "ended")

    def _log_end(self, name: str, event: str) -> None:
        if self.log.active:
            self.log.arm_state(self.arm.getActualQ(), self.arm.getActualTCPPose(), self.gripper.width,
                               self.gripper.force, self.arm.getActualTCPForce())
        self.log.stage(name, event)

    @cached_property
    def hang(self) -> DemoHang:
        """Where the task's demos hung the handle hole and how they carried (`app.predict.hole_places`),
        read and computed once per job."""
        return demo_hang(task_demos(self.config.predict.demos or DEMOS_DIR / self.t.demos))

    @cached_property
    def T_base_fixture_placed(self) -> np.ndarray:
        """The fixture's pose that places are planned for: moved clear of a peg by the motion settings'
        `peg_clearance` and `peg_short` (`app.motion.place_line.above_peg`); other fixtures as they are."""
        e = self.config.motion
        return above_peg(self.T_base_fixture, self.t.fixture, e.peg_clearance, e.peg_short)

    @cached_property
    def fixture_meshes(self) -> list[trimesh.Trimesh]:
        """The cell's fixtures, their meshes in the base frame (taken out of a look for an object that fell)."""
        return fixture_meshes(self.scene.layout)

    def release_width(self, held: float) -> float:
        """The fingers' opening (m) to let go of what they hold `held` wide: `JobConfig.release_clearance`
        beyond it, within the stroke."""
        return min(self.gripper.stroke, held + self.config.release_clearance)

    def guards_hang(self) -> bool:
        """Whether a hang's place line is guarded and searched beside (`app.jobs.guarded`), and its way out
        guarded too: a hang from a predicted place, whose hole is a centimetre or two off and whose mug
        may swing onto the peg as it is let go. A method that reads true poses (the oracle) hangs exactly:
        its lines run as planned (a 30 N stop would cut its hangs short), and a shelf's place line ends
        pressing on the shelf (docs/jobs.md)."""
        return not method_record(self.config.method).true_poses and is_hang(self.t)

    def guards_set_down(self) -> bool:
        """Whether a place on a fixture without a peg (a shelf) is set down under contact detection: a
        predicted place, which may be a few centimetres low (the oracle's ends pressing on the shelf)."""
        return not method_record(self.config.method).true_poses and not is_hang(self.t)

    def looks_for_hole(self) -> bool:
        """Whether the job tries places built from the handle hole: a hang by a method that does not read
        true poses, with `PredictConfig.hole_places` on."""
        return self.config.predict.hole_places and self.guards_hang()

    def place_line(self, cloud: np.ndarray) -> Callable[[Candidate], np.ndarray]:
        """Pair -> the direction of its line onto the fixture: one on which the object's seen points
        (N, 3), carried there, clear the fixture (a handle threads the peg; `app.motion.place_line`);
        for a hole place (place_rank < 0) the fixture's own approach, along the peg through the hole
        it saw - stray points at the hole's rim would tilt it onto the handle's bar."""
        def direction(c: Candidate) -> np.ndarray:
            if c.place_rank < 0:
                return fixture_approach(self.T_base_fixture, self.t.fixture)
            return peg_line_direction(transform_points(c.motion, cloud), self.T_base_fixture, self.t.fixture,
                                      self.config.motion.place_distances[0])
        return direction
