"""One operator teaching one task on the simulated cell, as on a real UR cell in freedrive.

The operator's steps, each a method that answers with a `Step` (ok, and one line saying what
happened or why not):

1. `new_object`: the cell is cleared, an object is put on the table and the Kinect's cloud of it is
   captured (what a demo keeps); the arm goes into teach mode (`Arm.teachMode`).
2. `guide(T_base_tcp)`: the operator's hand moves the TCP; the arm follows through IK, if a
   collision-free solution exists (arm and gripper against table, rack and shelf), else it stays
   and the step says why.
3. `close_gripper`: the gripper closes; the object counts as held if the gripper detects it and it
   rises with a 5 cm lift (`LIFT`).
4. `guide` again carries it (the operator holds the arm, the object moves with the fingers).
5. `release`: the fingers open where it is; the place judge (`app.simcell.judges`) rules on that pose.
6. `save_demo`: the grasp judge is run too, and a demo (cloud, poses, intrinsics, extrinsics) is
   written with the task's templates rebuilt, both in a staging folder swapped in whole
   (`app.tasks.staging`); nothing is saved half-way.

`try_imitation` puts an unseen object down and imitates the templates on its cloud, as a job would.
Judges run on copies of the object in a world of their own, so the live cell is never disturbed.
"""
from __future__ import annotations

import functools
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from app.failures import NoIKSolution, PerceptionFailure
from app.motion.ik import solve
from app.motion.scene import PlanningScene
from app.objects import split
from app.objects.library import LibraryObject
from app.perception import object_cloud
from app.predict.config import PredictConfig
from app.predict.predict import Prediction, predict
from app.simcell.cell import SimCell, add_fixtures
from app.simcell.judges import Verdict, judge_grasp, judge_place, judged_copy
from app.simcell.spawn import SpawnedObject, spawn
from app.tasks.demo import DEMO_GLOB, Demo, intrinsics_record, load_demo, save_demo
from app.tasks.demo_library import task_templates
from app.tasks.staging import staged
from app.tasks.task import Task
from hardware.se3 import invert, make_pose, pose_to_ur, rotvec_to_matrix, ur_to_pose
from hardware.sim.world import SimWorld, SimWorldConfig

LIFT = 0.05  # m the lift check raises a closed gripper
LIFT_KEPT = 0.8  # share of the lift the object must follow to count as held
SETTLE = 1.0  # s the cell runs after a release before the page shows it

Progress = Callable[[float, str], None]


def observed(step: Callable) -> Callable:
    """A step method whose answer (or refusal) is also handed to the session's observers, with its name."""
    @functools.wraps(step)
    def told(self: "TeachSession", *args, **kwargs) -> "Step":
        try:
            answer = step(self, *args, **kwargs)
        except ValueError as exc:
            answer = Step(False, str(exc))
            self._tell(step.__name__, answer)
            raise
        self._tell(step.__name__, answer)
        return answer
    return told


@dataclass(frozen=True)
class Step:
    """What an operator's step did: whether it worked, and one line saying what or why not."""

    ok: bool
    message: str


@dataclass
class Taught:
    """The demo being made: the object as seen, the grasp, the place and the judges' verdicts."""

    obj: SpawnedObject
    cloud: np.ndarray  # (N, 3) base frame, captured when the object was put down
    T_base_obj: np.ndarray  # where it stood then
    T_base_tcp: np.ndarray | None = None  # the TCP when the fingers closed on it
    T_tcp_obj: np.ndarray | None = None  # the object in the fingers, while held
    T_fixture_obj: np.ndarray | None = None  # where it was let go, relative to the fixture
    verdicts: dict[str, Verdict] = field(default_factory=dict)
    saved: str | None = None  # the demo this grasp and place were saved as: a second Save writes nothing

    @property
    def held(self) -> bool:
        return self.T_tcp_obj is not None


class TeachSession:
    """The live cell, the task's demo folder and the demo being made (thread-safe: one step at a time)."""

    def __init__(self, cell: SimCell, t: Task, out: Path, T_base_cam: np.ndarray,
                 source: LibraryObject | None = None, seed: int = 0) -> None:
        self.cell, self.task, self.out, self.T_base_cam, self.source = cell, t, Path(out), T_base_cam, source
        self.rng = np.random.default_rng(seed)
        self.scene = PlanningScene(cell.config)  # robot and gripper against table and fixtures
        self.judges = SimWorld(SimWorldConfig())
        self.judges.connect()
        self.judge_fixtures = add_fixtures(self.judges, cell.config)
        self.T_base_fixture = cell.config.fixture_pose(t.fixture)
        self.current: Taught | None = None
        self.prediction: Prediction | None = None
        self.lock = threading.RLock()
        self.observers: list[Callable[[TeachSession, str, Step], None]] = []  # told of every step (a recording)

    def close(self) -> None:
        self.scene.close()
        self.judges.disconnect()

    def _tell(self, name: str, step: Step) -> None:
        for observer in self.observers:
            observer(self, name, step)

    # state the page draws ------------------------------------------------------------------------
    def q(self) -> np.ndarray:
        return self.cell.arm.getActualQ()

    def tcp(self) -> np.ndarray:
        """The TCP's pose (4, 4) in the base frame."""
        return ur_to_pose(self.cell.arm.getActualTCPPose())

    def object_pose(self) -> np.ndarray | None:
        return None if self.current is None else self.cell.world.pose(self.current.obj.body)

    def demo_names(self) -> list[str]:
        return sorted(p.stem for p in self.out.glob(DEMO_GLOB)) if self.out.is_dir() else []

    def demo(self, name: str) -> Demo:
        """A saved demo by name, or a one-line error."""
        if name not in self.demo_names():
            raise ValueError(f"no demo {name!r} in {self.out}")
        return load_demo(self.out / f"{name}.npz")

    # the operator's steps --------------------------------------------------------------------------
    @observed
    def new_object(self, which: str = "train", instance: int | None = None,
                   placement: tuple[float, float, float] | None = None) -> Step:
        """Clear the cell, put an object down (`which` split, or the imported one) upright at a random
        place or at `placement` (x, y in metres, yaw in radians), capture its cloud."""
        with self.lock:
            self._clear()
            seeds = split(self.task.category, which)
            if instance is not None and self.source is None and instance not in seeds:
                raise ValueError(f"instance {instance} is not a {which}ing {self.task.category} "
                                 f"({seeds[0]}-{seeds[-1]})")
            seed = int(self.rng.choice(seeds)) if instance is None else int(instance)
            at = None if placement is None else make_pose(rotvec_to_matrix([0.0, 0.0, placement[2]]),
                                                          [placement[0], placement[1], 0.0])
            obj = spawn(self.cell.world, self.task.category, seed, "upright", rng=self.rng, source=self.source,
                        T_world_obj=at)
            try:
                cloud = object_cloud(self.cell.camera.capture(), self.T_base_cam)
            except PerceptionFailure as exc:
                self.cell.world.remove(obj.body)
                return Step(False, f"the camera does not see the object: {exc}")
            self.current = Taught(obj, cloud, self.cell.world.pose(obj.body))
            self.cell.arm.teachMode()
            return Step(True, f"{obj.label} on the table, {len(cloud)} points seen; guide the gripper to a grasp")

    @observed
    def guide(self, T_base_tcp: np.ndarray) -> Step:
        """Move the TCP to T_base_tcp by hand (freedrive), carrying a held object; why not, if it cannot."""
        with self.lock:
            arm, held = self.cell.arm, self.current is not None and self.current.held
            width = self.cell.gripper.width if held else self.scene.geometry.stroke
            try:
                with self.scene.fingers(width):
                    q = solve(self.scene.kinematics, T_base_tcp, arm.getActualQ(), self.scene, what="TCP")
            except NoIKSolution as exc:
                return Step(False, str(exc))
            if not arm.isTeachMode():
                arm.teachMode()
            arm.guide(q)
            if held:
                self.cell.world.set_pose(self.current.obj.body, self.tcp() @ self.current.T_tcp_obj)
            return Step(True, "carrying the object" if held else "following")

    @observed
    def close_gripper(self) -> Step:
        """Close the fingers; held if the gripper detects the object and it follows a LIFT-high lift."""
        with self.lock:
            taught = self._require(held=False)
            arm, gripper, world = self.cell.arm, self.cell.gripper, self.cell.world
            arm.endTeachMode()
            try:
                gripper.close()
                if not gripper.object_detected:
                    gripper.open()
                    return Step(False, "the fingers closed on nothing: guide them around the object")
                T_grasp = self.tcp()
                z0 = world.pose(taught.obj.body)[2, 3]
                lifted = T_grasp.copy()
                lifted[2, 3] += LIFT
                moved = arm.moveL(pose_to_ur(lifted), 0.1, 0.5)
                rose = world.pose(taught.obj.body)[2, 3] - z0
                if not moved or not gripper.object_detected or rose < LIFT_KEPT * LIFT:
                    why = arm.getLastError() if not moved else f"it rose {rose * 100:.1f} of {LIFT * 100:.0f} cm"
                    self._put_back(taught, T_grasp)
                    return Step(False, f"the lift check failed ({why}): not held; grasp it elsewhere")
                taught.T_base_tcp, taught.T_tcp_obj = T_grasp, invert(self.tcp()) @ world.pose(taught.obj.body)
                taught.saved = None  # a new grasp: a new demonstration
                taught.T_fixture_obj = None
                return Step(True, f"held: detected and lifted {rose * 100:.1f} cm; carry it to the {self.task.fixture}")
            finally:
                arm.teachMode()

    @observed
    def release(self) -> Step:
        """Open the fingers where the object is; the place judge's verdict on that pose."""
        with self.lock:
            taught = self._require(held=True)
            T_base_obj = self.cell.world.pose(taught.obj.body)
            taught.T_fixture_obj = invert(self.T_base_fixture) @ T_base_obj
            verdict = judged_copy(self.judges, taught.obj, T_base_obj, lambda o: judge_place(
                self.judges, o, T_base_obj, self.judge_fixtures[self.task.fixture], self.task.upright))
            taught.verdicts["place"], taught.T_tcp_obj, taught.saved = verdict, None, None  # a new place: unsaved
            self.cell.arm.endTeachMode()
            self.cell.gripper.open()
            self.cell.world.step(int(SETTLE / self.cell.world.config.time_step))
            self.cell.arm.teachMode()
            what = "placed" if verdict.success else "not placed"
            return Step(verdict.success, f"{what}: {verdict.reason}" + ("; save the demo" if verdict.success else ""))

    @observed
    def save_demo(self, progress: Progress = lambda f, s: None) -> Step:
        """Judge the grasp, write the demo and rebuild the templates (staged: whole or not at all)."""
        with self.lock:
            taught = self.current
            if taught is None or taught.T_base_tcp is None:
                raise ValueError("no grasp to save: close the gripper on an object first")
            if taught.T_fixture_obj is None:
                raise ValueError(f"no place to save: release the object on the {self.task.fixture} first")
            if not taught.verdicts["place"].success:
                raise ValueError(f"the place failed its judge ({taught.verdicts['place'].reason}): place it again")
            if taught.saved is not None:
                return Step(True, f"already saved as {taught.saved}: put down a new object to teach another demo")
            progress(0.1, "judging the grasp")
            grasp = judged_copy(self.judges, taught.obj, taught.T_base_obj,
                                lambda o: judge_grasp(self.judges, o, taught.T_base_tcp))
            if not grasp.success:
                raise ValueError(f"the grasp failed its judge ({grasp.reason}): grasp it again")
            demo = self._demo(taught, grasp)
            with staged(self.out, "add") as stage:
                save_demo(demo, stage / f"{demo.name}.npz")
                count = len(list(stage.glob(DEMO_GLOB)))
                progress(0.3, f"rebuilding the {self.task.name} templates from {count} demos")
                templates = task_templates(self.task, stage, rebuild=True)
            taught.saved = demo.name
            progress(1.0, "saved")
            sizes = ", ".join(f"{s} {len(tp.points)} points" for s, tp in templates.items())
            return Step(True, f"saved {demo.name}; templates rebuilt ({sizes})")

    @observed
    def delete_demo(self, name: str, progress: Progress = lambda f, s: None) -> Step:
        """Remove a saved demo and rebuild the templates from the others (staged)."""
        with self.lock:
            self.demo(name)
            with staged(self.out, "add") as stage:
                (stage / f"{name}.npz").unlink()
                left = len(list(stage.glob(DEMO_GLOB)))
                progress(0.3, f"rebuilding the templates from {left} demos")
                if left:
                    task_templates(self.task, stage, rebuild=True)
            progress(1.0, "deleted")
            return Step(True, f"deleted {name}; {left} demos left" + ("" if left else " (no templates)"))

    @observed
    def try_imitation(self, method: str = "nift") -> Step:
        """An unseen (test-split) object put down and the templates imitated on its cloud."""
        with self.lock:
            if not self.demo_names():
                raise ValueError("no demos yet: save one before trying the imitation")
            step = self.new_object("test")
            if not step.ok:
                return step
            self.prediction = predict(self.task, self.current.cloud, PredictConfig(method=method, demos=self.out),
                                      self.T_base_fixture)
            loss = {s: v[0] for s, v in self.prediction.losses.items() if v}
            return Step(True, f"{self.current.obj.label}: predicted grasp and place (template loss " +
                        ", ".join(f"{s} {v:.4f}" for s, v in loss.items()) + ")")

    # internals ------------------------------------------------------------------------------------
    def _require(self, held: bool) -> Taught:
        if self.current is None:
            raise ValueError("no object on the table: put one down first")
        if held and not self.current.held:
            raise ValueError("nothing is held: close the gripper on the object first")
        if not held and self.current.held:
            raise ValueError("the object is already held: release it first")
        return self.current

    def _clear(self) -> None:
        """Remove the object, open the gripper, put the arm home (the operator's reset)."""
        if self.current is not None:
            self.cell.world.remove(self.current.obj.body)
            self.current = None
        self.prediction = None
        arm = self.cell.arm
        arm.endTeachMode()
        if arm.isProtectiveStopped():
            arm.unlockProtectiveStop()
        self.cell.robot.reset_arm(np.asarray(self.cell.config.arm.home_q))
        self.cell.gripper.open()

    def _put_back(self, taught: Taught, T_grasp: np.ndarray) -> None:
        """After a failed lift: fingers open, the object back where it was seen, the TCP at the grasp."""
        self.cell.gripper.open()
        self.cell.world.set_pose(taught.obj.body, taught.T_base_obj)
        try:
            self.cell.robot.reset_arm(solve(self.scene.kinematics, T_grasp, self.q()))
        except NoIKSolution:
            pass

    def _demo(self, taught: Taught, grasp: Verdict) -> Demo:
        names = self.demo_names()
        index = 1 + max((int(n.split("-")[-1]) for n in names if n.split("-")[-1].isdigit()), default=-1)
        o = taught.obj
        return Demo(self.task.name, taught.cloud, taught.T_base_obj, taught.T_base_tcp, taught.T_fixture_obj,
                    self.T_base_fixture, self.T_base_cam, intrinsics_record(self.cell.camera.intrinsics),
                    o.category, o.seed,
                    o.scale, f"demo-{index:02d}", {"grasp": grasp.reason, "place": taught.verdicts["place"].reason},
                    object=o.source.name if o.source else "", taught="page")
