"""A pick-and-place job: capture -> perceive -> imitate -> plan -> approach -> grasp -> lift ->
carry -> place -> release -> retreat -> verify, through the device interfaces.

Every stage is timed; the first one that fails ends the job with its name and a one-line reason,
and the arm is then stopped (stopJ) with the gripper opened. What only a particular cell can do
(the simulator releasing an object it held in mid-air once the fingers close, checking where the
object came to rest, taking key-frame pictures) comes in through `JobHooks`.
"""
from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from app.motion.executor import OBJECT, ExecutionError, ExecutorConfig, Planner, execute
from app.motion.ik import NoIKSolution, reach_check
from app.motion.scene import PlanningScene
from app.nift.imitate import ImitationConfig
from app.perception import PerceptionConfig, object_cloud
from app.predict.predict import Prediction, predict
from app.tasks.task import Task
from hardware.interfaces import Arm, DepthCamera, Gripper
from hardware.kinematics import UR5Kinematics
from hardware.se3 import pose_to_ur, ur_to_pose

Predictor = Callable[[np.ndarray], Prediction]  # object cloud (N, 3), base frame -> grasp and place
STAGES = ("capture", "perceive", "imitate", "plan", "approach", "grasp", "lift", "carry", "place", "release",
          "retreat", "verify")


@dataclass(frozen=True)
class JobConfig:
    """How a job runs: the method, the grip, and the settings of perception, imitation and motion."""

    method: str = "nift"
    grasp_force: float = 40.0  # N
    release_clearance: float = 0.02  # m the fingers open beyond the held width to let go: opening fully
    # inside a bowl swept the far finger into its wall and dragged it off the shelf on the retreat
    demos: Path | None = None  # task directory (default demos/<task>)
    center_grasp: bool = True  # centre the grasp between the fingers and a hang on the peg (app.predict.grasp_centering, app.predict.peg_centering)
    align_grasp: bool = False  # turn the grasp square to the wall between the fingers (app.predict.grasp_alignment): off, as
    # one Kinect's normals at a rim are too far off (docs/additions.md, "Grasp alignment")
    feasible: bool = True  # prefer grasps that close on something, places the grasp can carry to, and poses
    # the cell can reach (app.predict.feasibility, app.motion.ik.reach_check)
    perception: PerceptionConfig = PerceptionConfig()
    imitation: ImitationConfig = ImitationConfig()
    executor: ExecutorConfig = ExecutorConfig()


class JobHooks:
    """Cell-specific steps of a job; this default does nothing and cannot verify the outcome."""

    def on_grasped(self) -> None:
        """The fingers have closed on the object."""

    def keyframe(self, label: str) -> None:
        """A stage has finished (take a picture, log, ...)."""

    def verify(self) -> tuple[bool, str]:
        """(success, why) once the object has been let go on the fixture."""
        return True, "not verified (this cell has no check of the final object pose)"


class JobFailed(RuntimeError):
    """A stage could not do its part."""


@dataclass
class JobResult:
    """What happened: success, the failing stage and why, timings, poses, the plan's figures."""

    task: str
    method: str
    success: bool = False
    failed_stage: str | None = None
    reason: str = ""
    seconds: dict[str, float] = field(default_factory=dict)  # wall time per stage
    poses: dict[str, list[float]] = field(default_factory=dict)  # UR poses [x y z rx ry rz], base frame
    plan: dict[str, float] = field(default_factory=dict)
    arm: str = ""  # the arm's state at the end
    info: dict = field(default_factory=dict)  # the cell's own facts (object, seed, ...)

    def record(self) -> dict:
        """JSON-ready."""
        return {"task": self.task, "method": self.method, "success": self.success, "failed_stage": self.failed_stage,
                "reason": self.reason, "seconds": self.seconds, "total_seconds": round(sum(self.seconds.values()), 3),
                "poses": self.poses, "plan": self.plan, "arm": self.arm, **self.info}


@contextmanager
def _stage(result: JobResult, name: str, hooks: JobHooks):
    """Time a stage; turn its expected errors into JobFailed(stage)."""
    start = time.perf_counter()
    try:
        yield
    except (JobFailed, NoIKSolution, ExecutionError, ValueError, FileNotFoundError) as exc:
        result.failed_stage = name
        raise JobFailed(str(exc)) from exc
    finally:
        result.seconds[name] = round(time.perf_counter() - start, 3)
    hooks.keyframe(name)


def run_job(t: Task, arm: Arm, gripper: Gripper, camera: DepthCamera, T_base_cam: np.ndarray,
            T_base_fixture: np.ndarray, scene: PlanningScene, config: JobConfig = JobConfig(),
            hooks: JobHooks | None = None, predictor: Predictor | None = None) -> JobResult:
    """Run one pick-and-place job of task t; never raises for a failed stage - it is in the result.

    `predictor(cloud)` gives the grasp and place; by default the configured method on the task's demos."""
    hooks = hooks or JobHooks()
    result = JobResult(t.name, config.method)
    kin = UR5Kinematics(tcp_offset=ur_to_pose(arm.getTCPOffset()))
    if predictor is None:
        def predictor(cloud: np.ndarray) -> Prediction:
            reachable = reach_check(kin, scene, arm.getActualQ(), ignore=(OBJECT,))
            return predict(t, cloud, config.method, T_base_fixture, config.demos, config.imitation,
                           center=config.center_grasp, feasible=config.feasible, reachable=reachable,
                           align=config.align_grasp)
    try:
        _run(t, arm, gripper, camera, T_base_cam, T_base_fixture, scene, kin, config, hooks, predictor, result)
        result.arm = "home"
    except JobFailed as exc:
        result.reason = str(exc)
        result.arm = _make_safe(arm, gripper)
    finally:
        scene.remove(OBJECT)
    return result


def _run(t, arm, gripper, camera, T_base_cam, T_base_fixture, scene, kin, config, hooks, predictor, result) -> None:
    planner = Planner(kin, arm.joint_limits, scene, config.executor)
    tolerance = config.executor.end_tolerance
    with _stage(result, "capture", hooks):
        frame = camera.capture()
    with _stage(result, "perceive", hooks):
        cloud = object_cloud(frame, T_base_cam, config.perception)
        scene.add_cloud(OBJECT, cloud, eye=T_base_cam[:3, 3])
    with _stage(result, "imitate", hooks):
        pred = predictor(cloud)
    with _stage(result, "plan", hooks):
        plan = planner.pick_place(arm.getActualQ(), pred.T_base_tcp, pred.T_base_tcp_place,
                                  t.place_direction(T_base_fixture))
        result.poses = {"grasp": _ur(plan.T_base_grasp), "place": _ur(plan.T_base_place)}
        result.plan = {"planning_seconds": round(plan.seconds, 3), "trajectory_seconds": round(plan.duration, 2),
                       "joint_travel_rad": round(plan.travel, 2)}
    with _stage(result, "approach", hooks):
        gripper.open()
        execute(arm, plan.segment("to pre-grasp"), tolerance)
        execute(arm, plan.segment("approach"), tolerance)
    with _stage(result, "grasp", hooks):
        if not gripper.close(config.grasp_force):
            raise JobFailed("grasp missed: the gripper closed on nothing")
        hooks.on_grasped()
    for name in ("lift", "carry"):
        with _stage(result, name, hooks):
            execute(arm, plan.segment(name), tolerance)
            if not gripper.object_detected:
                raise JobFailed(f"object dropped during the {name} (gripper width {1000 * gripper.width:.1f} mm)")
    with _stage(result, "place", hooks):
        execute(arm, plan.segment("place"), tolerance)
    with _stage(result, "release", hooks):
        gripper.open(width=min(gripper.stroke, gripper.width + config.release_clearance))
    with _stage(result, "retreat", hooks):
        for name in ("retreat", "clear", "home"):
            execute(arm, plan.segment(name), tolerance)
    with _stage(result, "verify", hooks):
        ok, why = hooks.verify()
        if not ok:
            raise JobFailed(f"place failed: {why}")
        result.success, result.reason = True, why


def _make_safe(arm: Arm, gripper: Gripper) -> str:
    """After a failure: stop the joints, open the gripper; say what state the arm is left in."""
    arm.stopJ()
    gripper.open()
    q = np.round(arm.getActualQ(), 3).tolist()
    return f"protective stop at q={q}" if arm.isProtectiveStopped() else f"stopped at q={q}, gripper open"


def _ur(T: np.ndarray) -> list[float]:
    return np.round(pose_to_ur(T), 5).tolist()
