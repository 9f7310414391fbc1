"""A pick-and-place job: capture -> perceive -> imitate -> plan -> approach -> grasp -> lift ->
carry -> place -> release -> retreat -> verify, through the device interfaces.

Every stage is timed; the first one that fails ends the job with its name and a one-line reason,
and the arm is then stopped (stopJ) with the gripper opened. What only a particular cell can do
(the simulator releasing an object it held in mid-air once the fingers close, checking where the
object came to rest, taking key-frame pictures) comes in through `JobHooks`.

Our additions, as a person at the cell would work:
- the plan takes the first grasp and place pair, in the order of the template loss, that the cell
  can execute (`app.jobs.choice`), not the single lowest-loss pose;
- the hold is checked after closing, after the lift and after the carry (the gripper's width and
  object_detected); on a miss the gripper opens, backs off along the approach, the arm goes home, the camera looks
  again and the next candidate with another grasp is tried (re-imitated when the object moved),
  up to `JobConfig.attempts` grasps. Every attempt goes in the record;
- after the release the camera checks that something new stands where the object was sent
  (`app.jobs.check`); a cell without a judge of its own reports that as the job's verdict. When it
  sees nothing new there at all (the object fell off the fixture) and attempts are left, the job
  looks for the object again and picks and places it again, as after a missed grasp.

The settings are in `app.jobs.settings`, the record and the hooks in `app.jobs.record`, the place
chosen after the second look in `app.jobs.held_place`.
"""
from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from app.categories import REVOLUTION
from app.failures import (CONNECTION_LOST, INTERNAL_ERROR, CellFailure, GraspMissed, GraspSlipped, NoCandidate, PlaceFailed, PlaceMissed,
                          ReleaseJammed)
from app.jobs.check import sighting
from app.jobs.choice import HELD, choose, describe
from app.jobs.clearance import approach_blocked, gripper_clear
from app.jobs.context import JobContext, Placer, Predictor
from app.jobs.guarded import guarded_leave, guarded_line, guarded_place, guarded_set_down
from app.jobs.held_place import look_and_place
from app.jobs.hold import holding, object_axis, on_object
from app.jobs.log import JobLog, LoggedCamera
from app.jobs.motion_meter import MeteredArm
from app.jobs.record import STAGES, JobHooks, JobResult, check_held, ur
from app.jobs.settings import JobConfig, is_hang, looks_again
from app.motion.executor import back_to_start, execute, motion_failure
from app.motion.ik import reach_failure
from app.motion.planner import OBJECT, FingerWidths, Planner
from app.motion.scene import PlanningScene
from app.motion.trajectory import reverse
from app.nift.imitate import use_threads
from app.perception import object_points, resample
from app.predict.pairs import Candidate
from app.predict.grasp_centering import held_width
from app.predict.hole_places import with_hole_pairs
from app.predict.predict import Prediction, predict, predict_place
from app.predict.palm_clearance import seated
from app.predict.turned_grasps import turned_pairs
from app.tasks.task import Task
from hardware.interfaces import Arm, DepthCamera, DeviceConnectionLost, Gripper
from hardware.kinematics import UR5Kinematics
from hardware.se3 import pose_to_ur, transform_points, ur_to_pose

__all__ = ["STAGES", "JobConfig", "JobHooks", "JobResult", "Predictor", "run_job"]
log = logging.getLogger(__name__)
MOVED = 0.01  # m: a cloud whose centroid moved more than this since the last look is imitated again
RELEASE_TOLERANCE = 0.005  # m: fingers this close to the opening asked have let go
RELEASE_FREED = 0.010  # m beyond the held width: fingers that opened this far have left what they held (a mug's
# inner finger may meet the far wall and stop short of the opening asked, the mug let go)
RELEASE_BACK_OFF = 0.002  # m back along the approach per try when the fingers jam on the release
RELEASE_TRIES = 3
RELEASE_SPEED, RELEASE_ACCELERATION = 0.02, 0.5  # m/s, m/s^2 of those few millimetres
APPROACH_BACK_OFF_SPEED = 0.05  # m/s back up the approach line after a contact stopped it
APPROACH_ARRIVED = 0.007  # m: an approach stopped by a contact this close to the grasp closes there (a palm that
# meets a bowl's rim a few mm short holds it when pressed on; docs/jobs.md)


def run_job(t: Task, arm: Arm, gripper: Gripper, camera: DepthCamera, T_base_cam: np.ndarray,
            T_base_fixture: np.ndarray, scene: PlanningScene, config: JobConfig = JobConfig(),
            hooks: JobHooks | None = None, predictor: Predictor | None = None,
            placer: Placer | None = None, job_log: JobLog | None = None) -> JobResult:
    """Run one pick-and-place job of task t; never raises for a failed stage - it is in the result, with
    its kind (`app.failures`); an exception that is no CellFailure is a bug: the result says
    "internal_error", the traceback goes to the log, and the arm is made safe as after a failure.

    `predictor(cloud)` gives the grasp and place; by default the configured method on the task's demos.
    A job that takes the second look (`config.second_look`; template methods only) chooses the place
    again with `placer(held cloud, grasp, starts)`; by default the method imitates it again. `job_log` hears
    what the job sees and does as it happens (`app.jobs.log`)."""
    hooks, job_log = hooks or JobHooks(), job_log or JobLog()
    result = JobResult(t.name, config.method)
    job_log.begin(t, config.method, arm.getTimestamp)
    if job_log.active:
        camera = LoggedCamera(camera, job_log, T_base_cam)
    use_threads(config.threads)
    kin = UR5Kinematics(tcp_offset=ur_to_pose(arm.getTCPOffset()))
    settings = config.predict
    if not looks_again(config, t):
        placer = None
    elif placer is None:
        def placer(cloud: np.ndarray, T_grasp: np.ndarray, starts: np.ndarray) -> list[Candidate]:
            return predict_place(t, cloud, T_grasp, settings, T_base_fixture, starts)
    if predictor is None:
        def predictor(cloud: np.ndarray) -> Prediction:
            return predict(t, cloud, settings, T_base_fixture,
                           gripper_clear(scene, cloud, config.table_z, config.motion.approach_distance,
                                         settings.center, settings.align))
    metered = MeteredArm(arm)  # what the job moved, for the record
    try:
        _run(JobContext(t, metered, gripper, camera, T_base_cam, T_base_fixture, scene, kin, config, hooks, predictor,
                        result, placer, log=job_log))
        result.arm = "home"
    except CellFailure as exc:
        result.reason, result.failure_kind = str(exc), exc.kind
        result.arm = _make_safe(arm, gripper)
    except DeviceConnectionLost as exc:  # nothing can be asked of the devices any more: no clean-up to try
        result.reason, result.failure_kind = f"{result.failed_stage}: {exc}", CONNECTION_LOST
        result.arm = "unknown: the connection to its controller was lost"
    except Exception as exc:  # noqa: BLE001 - a bug of ours: the record says so, the log has the traceback
        log.exception("job %s (%s) failed in stage %s", t.name, config.method, result.failed_stage)
        result.reason, result.failure_kind = f"internal error: {type(exc).__name__}: {exc}", INTERNAL_ERROR
        result.arm = _make_safe(arm, gripper)
    finally:
        scene.remove(OBJECT)
        result.motion = metered.record()
    job_log.end(result)
    return result


def _run(job: JobContext) -> None:
    if job.log.active:
        job.log.fixtures(job.fixture_meshes)
    planner = Planner(job.kin, job.arm.joint_limits, job.scene, job.config.motion, object_stays=not is_hang(job.t))
    options, seen, slips = None, None, []
    for attempt in range(1, job.config.attempts + 1):
        last = attempt == job.config.attempts
        cloud = _observe(job)
        if options is None or np.linalg.norm(cloud.mean(axis=0) - seen) > MOVED:
            options = _imitate(job, cloud)
        seen = cloud.mean(axis=0)
        pick, chosen = _plan(job, planner, _holding(job, options, slips), cloud)
        plan, sent = pick, transform_points(chosen.motion, cloud)  # sent: where the object should end
        try:
            _pick(job, pick, planner)
            if job.placer is not None:  # the rest planned again from the held views
                plan, sent = look_and_place(job, planner, pick, chosen, options, cloud)
            _carry(job, plan)
        except GraspMissed as miss:
            job.result.attempts.append({"attempt": attempt, **describe(chosen, str(miss))})
            if last:
                raise type(miss)(f"{miss} (attempt {attempt} of {attempt})") from None
            if isinstance(miss, GraspSlipped):  # it may lie anywhere now: the next look takes in the whole table
                slips.append(on_object(chosen.T_base_tcp[:3, 3], object_axis(job.points)))
                job.fell = True
            _recover(job, planner, pick)
            options = [c for c in options if c.grasp_rank != chosen.grasp_rank] or None  # none left: imitate again
            continue
        except CellFailure as failed:  # the attempt ends the job: its record says how
            job.result.attempts.append({"attempt": attempt, **describe(chosen, str(failed))})
            raise
        job.result.attempts.append({"attempt": attempt, **describe(chosen, HELD)})
        job.result.failed_stage = None
        try:
            _place(job, planner, plan, sent, again=not last)
            return
        except PlaceMissed as miss:  # the arm is home, the gripper open: look for the object where it fell
            job.result.attempts[-1]["outcome"] = str(miss)
            job.scene.remove(OBJECT)
            options, job.fell = None, True


def _observe(job: JobContext) -> np.ndarray:
    """Capture and perceive: the object's cloud (N, 3), added to the planning scene; after a place
    that missed, on the table around the fixtures too, the fixtures' points left out."""
    with job.stage("capture"):
        frame = job.camera.capture()
        job.first = job.first or frame
    with job.stage("perceive"):
        cfg = job.config.fallen_perception if job.fell else job.config.perception
        job.points = object_points(frame, job.T_base_cam, cfg, job.fixture_meshes if job.fell else ())
        cloud = resample(job.points, cfg.n_points, cfg.seed)
        job.scene.add_cloud(OBJECT, cloud, eye=job.T_base_cam[:3, 3])
        job.log.cloud(job.points, "fallen" if job.fell else "first look")
    return cloud


def _holding(job: JobContext, options: list, slips: list[np.ndarray]) -> list:
    """The options whose grasps will hold on what the camera saw, none near a grasp that slipped
    (`app.jobs.hold`); the record says why each other one was ruled out."""
    if not job.config.hold.check:
        return options
    kept, ruled = holding(options, job.points, job.T_base_cam[:3, 3], job.config.hold, slips)
    job.result.candidates += ruled
    return kept


def _imitate(job: JobContext, cloud: np.ndarray) -> list:
    """The predictor's candidate pairs, best first, their grasps seated as the cell makes them (off the
    table and off what lies under the palm: `app.predict.palm_clearance.seated`); the best one's poses go
    in the record at once."""
    with job.stage("imitate"):
        pred = job.predictor(cloud)
        job.log.prediction(pred)
        options = [replace(c, T_base_tcp=seated(c.T_base_tcp, cloud, job.config.table_z))
                   for c in pred.options()]
        if job.looks_for_hole():
            options, job.result.hole = with_hole_pairs(options, job.points, job.hang)
    job.result.poses = {"grasp": ur(pred.T_base_tcp), "place": ur(pred.T_base_tcp_place)}
    return options


def _plan(job: JobContext, planner: Planner, options: list, cloud: np.ndarray):
    """The first pair the cell can plan (`app.jobs.choice.choose`), its poses and figures recorded;
    while the object is held the fingers are modelled closed on what the cloud shows between them."""
    def widths(T_grasp: np.ndarray) -> FingerWidths:
        held, c, stroke = held_width(T_grasp, cloud), job.config, job.gripper.stroke
        return FingerWidths(min(stroke, held + c.approach_clearance), held, job.release_width(held))

    T_above = job.T_base_fixture_placed
    if T_above is not job.T_base_fixture:  # a peg: placed clear of it; other fixtures' pairs stay bit for bit
        options = [replace(c, T_base_fixture=T_above) for c in options]
    with job.stage("plan"):
        q = job.arm.getActualQ()
        failure = approach_blocked(reach_failure(job.kin, job.scene, q, ignore=(OBJECT,)), job.points,
                                   job.config.motion.approach_distance, lambda T: widths(T).approach,
                                   job.scene.geometry, APPROACH_ARRIVED)
        try:
            choice = choose(planner, options, q, job.place_line(cloud), failure,
                            job.config.most_plans, widths, pick_only=job.placer is not None)
        except NoCandidate as exc:
            job.result.candidates += exc.tried
            turned = turned_pairs(options, cloud) if job.t.category in REVOLUTION else []
            if not turned:
                raise
            try:  # the same grasps at another point of the rim or the neck: their own budget of plans
                choice = choose(planner, turned, q, job.place_line(cloud), failure, job.config.most_plans, widths)
            except NoCandidate as more:
                job.result.candidates += more.tried
                raise exc from None
        job.result.candidates += choice.tried
        plan = choice.plan
        job.log.chosen(choice.candidate, plan, job.kin)
        job.result.notes += plan.notes
        job.result.poses["grasp"] = ur(plan.T_base_grasp)
        if plan.T_base_place is not None:  # a pick alone keeps the first look's predicted place in the record
            job.result.poses["place"] = ur(plan.T_base_place)
        job.result.plan = {"planning_seconds": round(plan.seconds, 3), "trajectory_seconds": round(plan.duration, 2),
                           "joint_travel_rad": round(plan.travel, 2), "candidates_tried": len(choice.tried)}
    return plan, choice.candidate


def _pick(job: JobContext, plan, planner: Planner) -> None:
    """Approach, close, lift; GraspMissed when nothing is held after closing or after the lift."""
    tolerance = job.config.motion.end_tolerance
    with job.stage("approach"):
        job.gripper.open(width=plan.widths.approach if plan.widths else None)
        execute(job.arm, plan.segment("to pre-grasp"), tolerance)
        short = _guarded_approach(job, plan.segment("approach"))
    with job.stage("grasp"):
        if not job.gripper.close(job.config.grasp_force):
            raise GraspMissed("grasp missed: the gripper closed on nothing")
        job.hooks.on_grasped()
    with job.stage("lift"):
        lift = plan.segment("lift")
        if short:  # closed a few mm short of the grasp: the same lift, from there
            with job.scene.fingers(plan.widths.held if plan.widths else job.gripper.width):
                lift = planner.line(job.arm.getActualQ(), job.kin.fk(lift.end), "lift", (OBJECT,), gentle=True)
        execute(job.arm, lift, tolerance)
        check_held(job.gripper, "lift")


def _guarded_approach(job: JobContext, approach) -> float:
    """The approach line under contact detection: fingers that meet the object (a finger on a mug's
    rim instead of beside it) stop the arm at rest, it backs off to the pre-grasp and the attempt
    is a miss (GraspMissed: the next candidate is tried), rather than pressing on into a protective stop.
    A contact within `APPROACH_ARRIVED` of the grasp (the palm on a bowl's rim) is the grasp: returns
    how far short (m) the arm stopped there, 0 when it got there."""
    met, why = guarded_line(job, approach, job.config.approach_contact_force)
    if met is None:
        return 0.0
    if met <= APPROACH_ARRIVED:
        job.result.notes.append(f"approach: the tool met the object {1000 * met:.0f} mm before the grasp; closed there")
        return met
    if not job.arm.moveL(job.arm.getForwardKinematics(approach.q[0]), APPROACH_BACK_OFF_SPEED):
        raise motion_failure(job.arm, "approach: backing off after a contact")
    raise GraspMissed(f"approach: the tool met something {1000 * met:.0f} mm before the grasp ({why}); "
                      "backed off to the pre-grasp")


def _carry(job: JobContext, plan) -> None:
    """Carry to the pre-place; GraspMissed when the object slipped out on the way (it lies somewhere
    in the cell now: the next attempt looks for it again)."""
    with job.stage("carry"):
        execute(job.arm, plan.segment("carry"), job.config.motion.end_tolerance)
        check_held(job.gripper, "carry")


def _recover(job: JobContext, planner: Planner, pick) -> None:
    """After a miss: open, back off along the approach (when still at the grasp), go home (`pick`: the
    plan the grasp was made with)."""
    tolerance = job.config.motion.end_tolerance
    with job.stage("recover"):
        job.gripper.open()
        q = job.arm.getActualQ()
        if np.abs(q - pick.segment("lift").q[0]).max() < tolerance:
            execute(job.arm, reverse(pick.segment("approach")), tolerance)
        job.scene.remove(OBJECT)  # it may have moved; the next look adds it again
        home = np.asarray(job.config.motion.home_q)
        execute(job.arm, planner.transit(job.arm.getActualQ(), home, "recover"), tolerance)


def _place(job: JobContext, planner: Planner, plan, sent: np.ndarray, again: bool = False) -> None:
    """Place, release, retreat, verify (`sent`: the observed cloud moved where it should end); PlaceMissed
    when the camera sees nothing new where the object was sent and the job may try `again`."""
    tolerance = job.config.motion.end_tolerance
    with job.stage("place"):
        if job.guards_hang():
            short = guarded_place(job, plan.segment("place"))
        elif job.guards_set_down():
            short = guarded_set_down(job, plan.segment("place"))
        else:
            execute(job.arm, plan.segment("place"), tolerance)
            short = False
    with job.stage("release"):
        held = job.gripper.width
        released = job.release_width(held)
        _let_go(job, released, held)
    with job.stage("retreat"):
        if short:  # let go off the planned place: the way out is planned from there
            leave = planner.leave(job.arm.getActualQ(), released, job.t.fixture, plan.T_base_grasp)
        else:
            back_to_start(job.arm, plan.segment("retreat"), tolerance)  # letting go may have pushed the wrist
            leave = [s for s in plan.segments if s.label in ("retreat", "clear", "home")]
        guarded_leave(job, leave)
    with job.stage("verify"):
        seen = sighting(job.first, job.camera.capture(), job.T_base_cam, sent)
        verdict = (seen.placed(), seen.why())
        job.result.seen = f"{'placed' if verdict[0] else 'not placed'}: {verdict[1]}"
        if again and seen.absent():
            raise PlaceMissed(f"place missed: {verdict[1]}; looked for the object again")
        ok, why = job.hooks.verify(verdict)
        if not ok:
            raise PlaceFailed(f"place failed: {why}")
        job.result.success, job.result.reason = True, why


def _let_go(job: JobContext, asked: float, held: float) -> None:
    """Open the fingers from `held` to `asked` m; fingers that stop short of both the opening asked and
    `RELEASE_FREED` beyond the held width are jammed on the object (in the simulated cell: Bullet's
    finger-hull contacts lock, docs/jobs.md), so the tool backs off `RELEASE_BACK_OFF` along its
    approach, opens again and returns, up to `RELEASE_TRIES` times; ReleaseJammed when it still holds
    (retreating would carry the object away)."""
    job.gripper.open(width=asked)
    T_place = ur_to_pose(job.arm.getActualTCPPose())
    freed = min(asked - RELEASE_TOLERANCE, held + RELEASE_FREED)
    for tries in range(1, RELEASE_TRIES + 2):
        if job.gripper.width >= freed:
            break
        if tries > RELEASE_TRIES:
            raise ReleaseJammed(f"release: the fingers opened to {1000 * job.gripper.width:.1f} mm of the "
                            f"{1000 * asked:.1f} mm asked; the object may still be held")
        T = T_place.copy()
        T[:3, 3] -= tries * RELEASE_BACK_OFF * T_place[:3, 2]  # the tool's z is its approach axis
        if not job.arm.moveL(pose_to_ur(T), RELEASE_SPEED, RELEASE_ACCELERATION):
            raise motion_failure(job.arm, "release: backing off the jammed fingers")
        job.gripper.open(width=asked)
        job.result.notes.append(f"release: the fingers jammed; backed off {1000 * tries * RELEASE_BACK_OFF:.0f} mm "
                                f"and opened to {1000 * job.gripper.width:.1f} mm")
    if not np.allclose(ur_to_pose(job.arm.getActualTCPPose()), T_place, atol=1e-4) and not job.arm.moveL(
            pose_to_ur(T_place), RELEASE_SPEED, RELEASE_ACCELERATION):  # the planned retreat starts there
        raise motion_failure(job.arm, "release: returning to the place pose")


def _make_safe(arm: Arm, gripper: Gripper) -> str:
    """After a failure: stop the joints, open the gripper; say what state the arm is left in."""
    arm.stopJ()
    gripper.open()
    q = np.round(arm.getActualQ(), 3).tolist()
    return f"protective stop at q={q}" if arm.isProtectiveStopped() else f"stopped at q={q}, gripper open"


