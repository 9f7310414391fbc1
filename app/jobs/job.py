"""A pick-and-place job: capture -> perceive -> imitate -> plan -> approach -> grasp -> lift ->
carry -> place -> release -> retreat -> verify, through the device interfaces.

Every stage is timed; the first one that fails ends the job with its name and a one-line reason,
and the arm is then stopped (stopJ) with the gripper opened. What only a particular cell can do
(the simulator releasing an object it held in mid-air once the fingers close, checking where the
object came to rest, taking key-frame pictures) comes in through `JobHooks`.

Our additions, as a person at the cell would work:
- the plan takes the first grasp and place pair, in the order of the template loss, that the cell
  can execute (`app.jobs.choice`), not the single lowest-loss pose;
- the hold is checked after closing and after the lift (the gripper's width and object_detected);
  on a miss the gripper opens, backs off along the approach, the arm goes home, the camera looks
  again and the next candidate with another grasp is tried (re-imitated when the object moved),
  up to `JobConfig.attempts` grasps. Every attempt goes in the record;
- after the release the camera checks that something new stands where the object was sent
  (`app.jobs.check`); a cell without a judge of its own reports that as the job's verdict.
"""
from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from app.jobs.check import placed
from app.jobs.choice import NoCandidate, choose, describe
from app.jobs.clearance import gripper_clear
from app.jobs.second_look import SecondLookConfig, second_look
from app.motion.executor import (OBJECT, ExecutionError, ExecutorConfig, FingerWidths,
                                 Planner, execute, reverse)
from app.motion.ik import NoIKSolution, reach_failure
from app.motion.place_line import above_peg, peg_line_direction
from app.motion.scene import PlanningScene
from app.nift.candidates import CandidateConfig
from app.nift.imitate import ImitationConfig, use_threads
from app.objects import fixture
from app.perception import PerceptionConfig, object_points, resample
from app.predict.candidates import Candidate
from app.predict.grasp_centering import held_width
from app.predict.hole_places import with_hole_pairs
from app.predict.methods import ORACLE, TEMPLATE_METHODS
from app.predict.predict import Prediction, predict, predict_place
from app.predict.table_clearance import backed_off_table
from app.tasks.library import DEMOS_DIR, task_demos
from app.tasks.task import Task
from hardware.interfaces import Arm, DepthCamera, Frame, Gripper
from hardware.kinematics import UR5Kinematics
from hardware.se3 import pose_to_ur, transform_points, ur_to_pose

Predictor = Callable[[np.ndarray], Prediction]  # object cloud (N, 3), base frame -> grasp and place
# the held object's cloud as it stood when grasped, the grasp, places to start from -> place candidates
Placer = Callable[[np.ndarray, np.ndarray, np.ndarray], list[Candidate]]
STAGES = ("capture", "perceive", "imitate", "plan", "approach", "grasp", "lift", "recover", "look", "carry", "place",
          "release", "retreat", "verify")
# The cell's imitation schedule: prune every 10 steps down to 3 poses, one per basin, explore on 128
# points and refine on 256, leave out points of negligible weight, stop after 25 steps without gain,
# decay over 200 steps (docs/jobs.md, "Imitation time").
JOB_IMITATION = ImitationConfig(prune_every=10, explore_points=128, refine_points=256, patience=25, iterations=200,
                               keep=3, min_weight=1e-3, diverse=True, candidates=CandidateConfig(margin=0.3, most=8),
                               grasp_start_turns=2)
MOVED = 0.01  # m: a cloud whose centroid moved more than this since the last look is imitated again
RELEASE_TOLERANCE = 0.005  # m: fingers that stop farther than this short of the opening asked did not let go


@dataclass(frozen=True)
class JobConfig:
    """How a job runs: the method, the grip, and the settings of perception, imitation and motion."""

    method: str = "nift"
    grasp_force: float = 40.0  # N
    approach_clearance: float = 0.04  # m the fingers open beyond the held width on the approach: fully open
    # (85 mm), the inner finger of a rim grasp landed on the far wall of a small mug (4 of 50 oracle jobs)
    release_clearance: float = 0.04  # m the fingers open beyond the held width to let go: fully open,
    # the far finger inside a bowl swept its wall on the retreat; at 2 cm a bowl that had turned 4-5
    # degrees in the grasp still leant on a finger and was dragged off the shelf
    demos: Path | None = None  # task directory (default demos/<task>)
    center_grasp: bool = True  # centre the grasp between the fingers and a hang on the peg (app.predict.grasp_centering, app.predict.peg_centering)
    align_grasp: bool = False  # turn the grasp square to the wall between the fingers (app.predict.grasp_alignment): off, as
    # one Kinect's normals at a rim are too far off (docs/additions.md, "Grasp alignment")
    feasible: bool = True  # prefer grasps that close on something and places the grasp can carry to
    # (app.predict.feasibility); what the cell can reach is chosen among the candidates (app.jobs.choice)
    carried_grasps: bool = True  # also try the demos' grasps carried from each place (app.predict.carried_grasps)
    table_z: float = 0.0  # m, the table top in the base frame (the cell's layout)
    hole_places: bool = True  # a hang also tries the places that put the handle hole seen in the cloud where
    # the demos had it, first (app.predict.hole_places); not for the oracle, whose poses are true
    second_look: bool | None = None  # show the held object to the camera and choose the place again from what
    # it shows (app.jobs.second_look); None: on for hangs, where the held views show the handle hole
    # (mug 5/20 -> 12/20), off otherwise (bowls 10/10 -> 7/10 when it imitated the place again; docs/jobs.md)
    look: SecondLookConfig = SecondLookConfig()
    attempts: int = 3  # grasps tried before the job gives up
    most_plans: int = 6  # full plans tried per attempt before the plan stage gives up
    threads: int = 1  # torch threads: two threads beside one busy process took 2.5x as long as one (docs/jobs.md)
    perception: PerceptionConfig = PerceptionConfig()
    imitation: ImitationConfig = JOB_IMITATION
    executor: ExecutorConfig = ExecutorConfig()

    def __post_init__(self) -> None:
        for name in ("attempts", "most_plans", "threads"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 1:
                raise ValueError(f"job setting {name} must be an integer >= 1, got {getattr(self, name)!r}")


class JobHooks:
    """Cell-specific steps of a job; this default does nothing and cannot verify the outcome."""

    def on_grasped(self) -> None:
        """The fingers have closed on the object."""

    def keyframe(self, label: str) -> None:
        """A stage has finished (take a picture, log, ...)."""

    def verify(self, seen: tuple[bool, str]) -> tuple[bool, str]:
        """(success, why) once the object has been let go on the fixture; `seen` is the job's own
        camera check (`app.jobs.check.placed`), which this default reports."""
        return seen


class JobFailed(RuntimeError):
    """A stage could not do its part."""


class GraspMissed(JobFailed):
    """The gripper holds nothing after closing or after the lift."""


@dataclass
class JobResult:
    """What happened: success, the failing stage and why, timings, poses, the plan's figures, and
    every candidate pair looked at and every grasp attempted."""

    task: str
    method: str
    success: bool = False
    failed_stage: str | None = None
    reason: str = ""
    seconds: dict[str, float] = field(default_factory=dict)  # wall time per stage, summed over attempts
    poses: dict[str, list[float]] = field(default_factory=dict)  # UR poses [x y z rx ry rz], base frame
    plan: dict[str, float] = field(default_factory=dict)
    arm: str = ""  # the arm's state at the end
    seen: str = ""  # the job's own camera check after the release (`app.jobs.check`)
    candidates: list[dict] = field(default_factory=list)  # every pair the plan stage looked at (`choice.describe`)
    attempts: list[dict] = field(default_factory=list)  # one per grasp: its candidate and the outcome
    look: dict = field(default_factory=dict)  # the second look: points seen, the place it chose, how far it moved
    hole: dict = field(default_factory=dict)  # the handle hole seen in the cloud, if a hang looks for one
    info: dict = field(default_factory=dict)  # the cell's own facts (object, seed, ...)

    def record(self) -> dict:
        """JSON-ready."""
        return {"task": self.task, "method": self.method, "success": self.success, "failed_stage": self.failed_stage,
                "reason": self.reason, "seconds": self.seconds, "total_seconds": round(sum(self.seconds.values()), 3),
                "poses": self.poses, "plan": self.plan, "arm": self.arm, "seen": self.seen, "candidates": self.candidates,
                "attempts": self.attempts, "look": self.look, "hole": self.hole, **self.info}


@contextmanager
def _stage(result: JobResult, name: str, hooks: JobHooks):
    """Time a stage (summed over attempts); turn its expected errors into JobFailed(stage)."""
    start = time.perf_counter()
    try:
        yield
    except (JobFailed, NoIKSolution, ExecutionError, ValueError, FileNotFoundError) as exc:
        result.failed_stage = name
        if isinstance(exc, JobFailed):
            raise
        raise JobFailed(str(exc)) from exc
    finally:
        result.seconds[name] = round(result.seconds.get(name, 0.0) + time.perf_counter() - start, 3)
    hooks.keyframe(name)


def run_job(t: Task, arm: Arm, gripper: Gripper, camera: DepthCamera, T_base_cam: np.ndarray,
            T_base_fixture: np.ndarray, scene: PlanningScene, config: JobConfig = JobConfig(),
            hooks: JobHooks | None = None, predictor: Predictor | None = None) -> JobResult:
    """Run one pick-and-place job of task t; never raises for a failed stage - it is in the result.

    `predictor(cloud)` gives the grasp and place; by default the configured method on the task's demos.
    A template method (not cpd, not the oracle) imitates the place again after the second look
    (`config.second_look`)."""
    hooks = hooks or JobHooks()
    result = JobResult(t.name, config.method)
    use_threads(config.threads)
    kin = UR5Kinematics(tcp_offset=ur_to_pose(arm.getTCPOffset()))
    placer = None
    if looks_again(config, t):
        def placer(cloud: np.ndarray, T_grasp: np.ndarray, starts: np.ndarray) -> list[Candidate]:
            return predict_place(t, cloud, T_grasp, config.method, T_base_fixture, config.demos, config.imitation,
                                 starts, center=config.center_grasp)
    if predictor is None:
        def predictor(cloud: np.ndarray) -> Prediction:
            return predict(t, cloud, config.method, T_base_fixture, config.demos, config.imitation,
                           center=config.center_grasp, feasible=config.feasible, align=config.align_grasp,
                           reachable=gripper_clear(scene, cloud, config.table_z, config.executor.approach_distance,
                                                   config.center_grasp, config.align_grasp),
                           carried_grasps=config.carried_grasps)
    try:
        _run(_Job(t, arm, gripper, camera, T_base_cam, T_base_fixture, scene, kin, config, hooks, predictor, result,
                  placer))
        result.arm = "home"
    except JobFailed as exc:
        result.reason = str(exc)
        result.arm = _make_safe(arm, gripper)
    finally:
        scene.remove(OBJECT)
    return result


def looks_again(config: JobConfig, t: Task) -> bool:
    """Whether a job of task t takes the second look: as configured, by default for a hang (a fixture
    with a peg); template methods only (not cpd, not the oracle)."""
    on = _is_hang(t) if config.second_look is None else config.second_look
    return on and config.method in TEMPLATE_METHODS


def _is_hang(t: Task) -> bool:
    return "peg_origin" in fixture(t.fixture).landmarks


@dataclass
class _Job:
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

    def stage(self, name: str):
        return _stage(self.result, name, self.hooks)


def _run(job: _Job) -> None:
    planner = Planner(job.kin, job.arm.joint_limits, job.scene, job.config.executor)
    options, seen = None, None
    for attempt in range(1, job.config.attempts + 1):
        cloud = _observe(job)
        if options is None or np.linalg.norm(cloud.mean(axis=0) - seen) > MOVED:
            options = _imitate(job, cloud)
        seen = cloud.mean(axis=0)
        plan, chosen = _plan(job, planner, options, cloud)
        sent = transform_points(chosen.motion, cloud)  # where the object should end
        try:
            _pick(job, plan)
            if job.placer is not None:
                plan, sent = _look(job, planner, plan, chosen, options, cloud)
        except GraspMissed as miss:
            job.result.attempts.append({"attempt": attempt, **describe(chosen, str(miss))})
            if attempt == job.config.attempts:
                raise JobFailed(f"{miss} (attempt {attempt} of {attempt})") from None
            _recover(job, planner, plan)
            options = [c for c in options if c.grasp_rank != chosen.grasp_rank]
            continue
        except JobFailed as failed:  # the attempt ends the job: its record says how
            job.result.attempts.append({"attempt": attempt, **describe(chosen, str(failed))})
            raise
        job.result.attempts.append({"attempt": attempt, **describe(chosen, "held")})
        job.result.failed_stage = None
        break
    _place(job, plan, sent)


def _observe(job: _Job) -> np.ndarray:
    """Capture and perceive: the object's cloud (N, 3), added to the planning scene."""
    with job.stage("capture"):
        frame = job.camera.capture()
        job.first = job.first or frame
    with job.stage("perceive"):
        job.points = object_points(frame, job.T_base_cam, job.config.perception)
        cloud = resample(job.points, job.config.perception.n_points, job.config.perception.seed)
        job.scene.add_cloud(OBJECT, cloud, eye=job.T_base_cam[:3, 3])
    return cloud


def _imitate(job: _Job, cloud: np.ndarray) -> list:
    """The predictor's candidate pairs, best first, their grasps backed off the table
    (`app.predict.table_clearance`); the best one's poses go in the record at once."""
    with job.stage("imitate"):
        pred = job.predictor(cloud)
        options = [replace(c, T_base_tcp=backed_off_table(c.T_base_tcp, cloud, job.config.table_z))
                   for c in pred.options()]
        if _looks_for_hole(job):
            options, job.result.hole = with_hole_pairs(options, job.points, _demos(job))
    job.result.poses = {"grasp": _ur(pred.T_base_tcp), "place": _ur(pred.T_base_tcp_place)}
    return options


def _demos(job: _Job) -> list:
    """The task's demos (for the hole they hung, `app.predict.hole_places`)."""
    return task_demos(job.config.demos or DEMOS_DIR / job.t.demos)


def _looks_for_hole(job: _Job) -> bool:
    """Whether the job tries places built from the handle hole: a hang (a fixture with a peg) by a method
    that is not the oracle, with `hole_places` on."""
    return job.config.hole_places and job.config.method != ORACLE and _is_hang(job.t)


def _plan(job: _Job, planner: Planner, options: list, cloud: np.ndarray):
    """The first pair the cell can plan (`app.jobs.choice.choose`), its poses and figures recorded;
    while the object is held the fingers are modelled closed on what the cloud shows between them."""
    def widths(T_grasp: np.ndarray) -> FingerWidths:
        held, c, stroke = held_width(T_grasp, cloud), job.config, job.gripper.stroke
        return FingerWidths(min(stroke, held + c.approach_clearance), held, min(stroke, held + c.release_clearance))

    T_above = above_peg(job.T_base_fixture, job.t.fixture, job.config.executor.peg_clearance)
    if T_above is not job.T_base_fixture:  # a peg: placed clear of it; other fixtures' pairs stay bit for bit
        options = [replace(c, T_base_fixture=T_above) for c in options]
    with job.stage("plan"):
        q = job.arm.getActualQ()
        failure = reach_failure(job.kin, job.scene, q, ignore=(OBJECT,))
        try:
            choice = choose(planner, options, q, _place_line(job, cloud), failure,
                            job.config.most_plans, widths, pick_only=job.placer is not None)
        except NoCandidate as exc:
            job.result.candidates += exc.tried
            raise
        job.result.candidates += choice.tried
        plan = choice.plan
        job.result.poses["grasp"] = _ur(plan.T_base_grasp)
        if plan.T_base_place is not None:  # a pick alone keeps the first look's predicted place in the record
            job.result.poses["place"] = _ur(plan.T_base_place)
        job.result.plan = {"planning_seconds": round(plan.seconds, 3), "trajectory_seconds": round(plan.duration, 2),
                           "joint_travel_rad": round(plan.travel, 2), "candidates_tried": len(choice.tried)}
    return plan, choice.candidate


def _place_line(job: _Job, cloud: np.ndarray):
    """Pair -> the direction of its line onto the fixture: one on which the object's seen points,
    carried there, clear the fixture (a handle threads the peg; `app.motion.place_line`)."""
    def direction(c: Candidate) -> np.ndarray:
        return peg_line_direction(transform_points(c.motion, cloud), job.T_base_fixture, job.t.fixture,
                                  job.config.executor.place_distance)
    return direction


def _pick(job: _Job, plan) -> None:
    """Approach, close, lift; GraspMissed when nothing is held after closing or after the lift."""
    tolerance = job.config.executor.end_tolerance
    with job.stage("approach"):
        job.gripper.open(width=plan.widths.approach if plan.widths else None)
        execute(job.arm, plan.segment("to pre-grasp"), tolerance)
        execute(job.arm, plan.segment("approach"), tolerance)
    with job.stage("grasp"):
        if not job.gripper.close(job.config.grasp_force):
            raise GraspMissed("grasp missed: the gripper closed on nothing")
        job.hooks.on_grasped()
    with job.stage("lift"):
        execute(job.arm, plan.segment("lift"), tolerance)
        if not job.gripper.object_detected:
            raise GraspMissed(f"object dropped during the lift (gripper width {1000 * job.gripper.width:.1f} mm)")


def _recover(job: _Job, planner: Planner, plan) -> None:
    """After a miss: open, back off along the approach (when still at the grasp), go home."""
    tolerance = job.config.executor.end_tolerance
    with job.stage("recover"):
        job.gripper.open()
        q = job.arm.getActualQ()
        if np.abs(q - plan.segment("lift").q[0]).max() < tolerance:
            execute(job.arm, reverse(plan.segment("approach")), tolerance)
        job.scene.remove(OBJECT)  # it may have moved; the next look adds it again
        home = np.asarray(job.config.executor.home_q)
        execute(job.arm, planner.transit(job.arm.getActualQ(), home, "recover"), tolerance)


def _look(job: _Job, planner: Planner, plan, chosen: Candidate, options: list, cloud: np.ndarray):
    """The second look (`app.jobs.second_look`): show the held object, imitate the place again on both
    views, and plan the rest from where the arm is - with the first look's places for this grasp when
    no new one plans (or nothing was seen). Returns the plan to carry on with and where the object
    should end (`sent`)."""
    T_grasp, width = plan.T_base_grasp, job.gripper.width
    widths = FingerWidths(width, width, width + job.config.release_clearance)
    T_above = above_peg(job.T_base_fixture, job.t.fixture, job.config.executor.peg_clearance)
    first = [chosen, *(c for c in options if c.grasp_rank == chosen.grasp_rank and c.place_rank != chosen.place_rank)]
    with job.stage("look"):
        holes = [(c, cloud) for c in first if c.place_rank < 0]  # the first look's hole places, first
        try:
            views = second_look(job.arm, job.camera, planner, job.T_base_cam, job.points, T_grasp, width,
                                job.config.executor.end_tolerance, job.config.look, job.config.perception)
        except (ValueError, NoIKSolution) as exc:  # nothing seen, or no way to show it: go on with the first look
            views, look = None, {"used": False, "why": str(exc)}
        if not job.gripper.object_detected:
            raise GraspMissed(f"object dropped during the second look (gripper width {1000 * job.gripper.width:.1f} mm)")
        fused, tries = None, []
        if views is not None:
            points = np.concatenate([job.points, *views])
            fused = resample(points, len(cloud), job.config.perception.seed)
            starts = np.stack([c.T_base_fixture_seen for c in first])
            look = {"used": False, "new_points": int(sum(len(v) for v in views))}
            tries = [(c, fused) for c in job.placer(fused, chosen.T_base_tcp, starts)[: job.config.most_plans]]
            if _looks_for_hole(job):
                held, look["hole"] = _held_hole(job, chosen, views if holes else [*views, points])
                holes = [(c, fused) for c in held] + holes
        tries = holes + tries + [(c, cloud) for c in first[: job.config.most_plans] if c.place_rank >= 0]
        q, whys, fused_whys = job.arm.getActualQ(), [], []
        for c, seen in tries:
            c = replace(c, T_base_fixture=T_above)  # placed clear of a peg, as the first look's pairs
            try:
                rest = planner.place_from(q, T_grasp, c.motion @ T_grasp, _place_line(job, seen)(c), widths)
            except NoIKSolution as exc:
                whys.append(str(exc))
                if seen is fused:
                    fused_whys.append(whys[-1])
                continue
            if seen is fused:
                look.update({"used": True, "place_rank": c.place_rank, **_moved(plan, rest)})
            elif fused is not None:  # why the fused cloud's best place was not taken
                look["why"] = fused_whys[0] if fused_whys else "no place"
            job.result.look = look
            job.result.poses["place"] = _ur(rest.T_base_place)
            return rest, transform_points(c.motion, seen)
        if fused is not None:
            look["why"] = fused_whys[0] if fused_whys else "no place"
        job.result.look = look
        raise JobFailed(f"none of {len(tries)} places could be planned for the held grasp; the best: "
                        f"{whys[0] if whys else 'no place'}")


def _held_hole(job: _Job, chosen: Candidate, clouds: list[np.ndarray]) -> tuple[list[Candidate], dict]:
    """The hole places for the held grasp from the first of `clouds` (grasp-time frame) that shows the
    hole - a view alone shows the object as it sits in the hand now, which may have turned on closing -
    and what was found (with the index of that cloud)."""
    found = {"found": False, "why": "no view shows the handle hole"}
    for i, points in enumerate(clouds):
        pairs, found = with_hole_pairs([chosen], points, _demos(job))
        if found["found"]:
            return [c for c in pairs if c.place_rank < 0], {**found, "view": i}
    return [], found


def _moved(plan, rest) -> dict:
    """How far the second look moved the place from the first plan's (or that the first had none)."""
    if plan.T_base_place is None:
        return {"pick_only": True}
    return {"place_moved_m": round(float(np.linalg.norm(rest.T_base_place[:3, 3] - plan.T_base_place[:3, 3])), 4)}


def _place(job: _Job, plan, sent: np.ndarray) -> None:
    """Carry, place, release, retreat, verify (`sent`: the observed cloud moved where it should end)."""
    tolerance = job.config.executor.end_tolerance
    with job.stage("carry"):
        execute(job.arm, plan.segment("carry"), tolerance)
        if not job.gripper.object_detected:
            raise JobFailed(f"object dropped during the carry (gripper width {1000 * job.gripper.width:.1f} mm)")
    with job.stage("place"):
        execute(job.arm, plan.segment("place"), tolerance)
    with job.stage("release"):
        asked = min(job.gripper.stroke, job.gripper.width + job.config.release_clearance)
        job.gripper.open(width=asked)
        if job.gripper.width < asked - RELEASE_TOLERANCE:  # retreating now would carry the object away
            raise JobFailed(f"release: the fingers opened to {1000 * job.gripper.width:.1f} mm of the "
                            f"{1000 * asked:.1f} mm asked; the object may still be held")
    with job.stage("retreat"):
        for name in ("retreat", "clear", "home"):
            execute(job.arm, plan.segment(name), tolerance)
    with job.stage("verify"):
        seen = placed(job.first, job.camera.capture(), job.T_base_cam, sent)
        job.result.seen = f"{'placed' if seen[0] else 'not placed'}: {seen[1]}"
        ok, why = job.hooks.verify(seen)
        if not ok:
            raise JobFailed(f"place failed: {why}")
        job.result.success, job.result.reason = True, why


def _make_safe(arm: Arm, gripper: Gripper) -> str:
    """After a failure: stop the joints, open the gripper; say what state the arm is left in."""
    arm.stopJ()
    gripper.open()
    q = np.round(arm.getActualQ(), 3).tolist()
    return f"protective stop at q={q}" if arm.isProtectiveStopped() else f"stopped at q={q}, gripper open"


def _ur(T: np.ndarray) -> list[float]:
    return np.round(pose_to_ur(T), 5).tolist()
