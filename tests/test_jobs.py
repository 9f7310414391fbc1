"""Pick-and-place jobs in the simulated cell, where physics decides: jobs succeed end to end, objects are let go
where they were put, the same seed gives the same job (the state machine's branches: test_job_branches.py)."""
from dataclasses import replace

import numpy as np
import pytest

from app.jobs.job import JobConfig
from app.motion.scene import PlanningScene
from app.simcell.cell import CellConfig, SimCell
from app.simcell.sim_job import JobSpec, SimHooks, run_series, run_sim_job
from app.tasks.task import task
from hardware.se3 import make_pose


def _run(config: CellConfig, spec: JobSpec, method: str, record=None):
    with SimCell(config) as cell:
        scene = PlanningScene(config)
        try:
            T_base_cam = np.array(cell.camera.config.T_base_cam)  # calibration is tested on its own
            result = run_sim_job(cell, scene, T_base_cam, spec, JobConfig.of(method), record)
            return result, cell.arm.getActualQ(), cell.gripper.width, cell.arm.isProtectiveStopped()
        finally:
            scene.close()


@pytest.mark.slow
# bottle upright seed 0 (the retreat used to drag the let-go bottle off the shelf): see
# test_an_object_let_go_on_the_shelf_stays_where_it_was_put
@pytest.mark.parametrize("name, pose, seed", [("mug", "upright", 0), ("bowl", "upright", 0), ("bottle", "upright", 1),
                                              ("mug", "resting", 1), ("bowl", "resting", 0), ("bottle", "resting", 1)])
def test_teacher_job_succeeds_end_to_end(name, pose, seed, tmp_path):
    """The oracle's job, upright and lying as it fell (seeds where a demo-like grasp exists)."""
    spec = JobSpec(task(name), seed=seed, pose=pose)
    result, q, width, stopped = _run(CellConfig(), spec, "teacher", tmp_path / "job.png")
    assert result.success, result.reason
    assert [s for s in result.seconds] == ["capture", "perceive", "imitate", "plan", "approach", "grasp", "lift",
                                           "carry", "place", "release", "retreat", "verify"]
    assert np.allclose(q, CellConfig().arm.home_q, atol=0.02) and not stopped
    assert (tmp_path / "job.png").stat().st_size > 10_000


@pytest.mark.slow
def test_a_pre_place_where_the_held_hull_meets_the_rack_moves_farther_out_along_the_peg():
    """The oracle's lying mug 33: at the pre-place 10 cm out along the place line the hull of the held
    cloud (which fills the handle) meets the rack, so no carry could end there; 20 cm out it is clear,
    and the mug hangs."""
    result, q, width, stopped = _run(CellConfig(), JobSpec(task("mug"), seed=33, pose="resting"), "teacher")
    assert result.success, result.reason
    assert result.plan["trajectory_seconds"] > 0 and not stopped


@pytest.mark.slow
@pytest.mark.parametrize("seed", [3, 14])
def test_nift_hangs_a_mug_end_to_end_by_the_hole_it_sees(seed):
    """NIFT's own job from the one Kinect (the README's first command): the mug hangs on the rack, by
    a place built from the handle hole one of the held views showed (seed 3: the half-turn, the first
    view missed it; seed 14: as the lift left it)."""
    result, q, _, stopped = _run(CellConfig(), JobSpec(task("mug"), seed=seed), "nift")
    assert result.success, result.reason
    assert result.look["used"] and result.look["place_rank"] < 0 and result.look["hole"]["found"]
    assert result.look["hole"]["view"] == {3: 1, 14: 0}[seed]
    assert np.allclose(q, CellConfig().arm.home_q, atol=0.02) and not stopped


def _sim(spec: JobSpec, job: JobConfig = JobConfig.of("teacher"), config: CellConfig = CellConfig(), **kwargs):
    with SimCell(config) as cell:
        scene = PlanningScene(config)
        try:
            T_base_cam = np.array(cell.camera.config.T_base_cam)
            return run_sim_job(cell, scene, T_base_cam, spec, job, **kwargs)
        finally:
            scene.close()


class DropsTheObjectOnce(SimHooks):
    """Once the first lift is done (the hold confirmed), the fingers open: the object falls back to
    the table while the arm carries on."""

    dropped = False
    after = "lift"

    def keyframe(self, label: str) -> None:
        super().keyframe(label)
        if label == self.after and not self.dropped:
            self.cell.gripper.open()
            self.dropped = True


class DropsTheObjectAfterTheLook(DropsTheObjectOnce):
    after = "look"


@pytest.mark.slow
def test_a_mug_dropped_on_the_carry_after_the_second_look_is_picked_again():
    """After the look the rest is planned from the held views (no lift in that plan): the recovery
    backs off with the pick's plan, and the mug is imitated and picked again where it fell. Where it
    falls decides whether the re-picked hang succeeds (of seed 0 the second look shows no handle hole
    and the hang meets the rack; seed 1 succeeded on one machine and not on another, whose floating
    point differs): every seed tried must drop and recover, and one of three must then succeed."""
    reasons = []
    for seed in (1, 2, 3):
        result = _sim(JobSpec(task("mug"), seed=seed), JobConfig(), hooks_type=DropsTheObjectAfterTheLook)
        assert "dropped during the carry" in result.attempts[0]["outcome"]
        assert len(result.attempts) >= 2 and "recover" in result.seconds
        if result.success:
            return
        reasons.append(result.reason)
    pytest.fail(f"no re-picked mug succeeded: {reasons}")


@pytest.mark.slow
def test_a_mug_whose_inner_finger_meets_the_far_wall_is_let_go():
    """The oracle's mug of seed 19: on the release its fingers stop at 28 mm of the 47 mm asked (the
    inner one on the mug's far wall), 20 mm beyond the rim they held: the mug is let go and hangs.
    Judged by the opening asked alone it was held, and three back-offs later the job failed."""
    result = _sim(JobSpec(task("mug"), seed=19))
    assert result.success, result.reason
    assert result.notes == []


@pytest.mark.slow
@pytest.mark.parametrize("name, seed", [("bowl", 4), ("bowl", 30), ("bottle", 0)])
def test_an_object_let_go_on_the_shelf_stays_where_it_was_put(name, seed):
    """The oracle's bowls of seeds 4 and 30 and bottle of seed 0: the fingers opened on contact points
    Bullet had kept with reversed normals; seed 4's opening finger dragged the bowl 2 cm along and the
    retreat off the shelf, seed 30's fingers locked at 7 mm, and the bottle left the shelf with the
    retreat. The gripper now forgets its contacts as it opens (`SimGripper._forget_finger_contacts`):
    the object stays within 5 mm of where the release found it, let go at the first opening."""
    at = {}

    class Watch(SimHooks):
        def keyframe(self, label: str) -> None:
            if label in ("place", "release"):
                at[label] = self.cell.world.pose(self.obj.body)[:3, 3]

    result = _sim(JobSpec(task(name), seed=seed), hooks_type=Watch)
    assert result.success, result.reason
    assert result.notes == []  # let go at the first opening
    assert np.linalg.norm(at["release"] - at["place"]) < 0.005


def test_a_pose_where_every_grasp_is_in_the_table_says_no_grasp_like_the_demos_exists():
    from contextlib import nullcontext
    from types import SimpleNamespace

    from app.failures import NoCandidate, NoDemoLikeGrasp
    from app.jobs.choice import NO_DEMO_LIKE_GRASP, choose
    from app.motion.ik import Blocked
    from app.predict.pairs import Candidate

    planner = SimpleNamespace(scene=SimpleNamespace(geometry=SimpleNamespace(stroke=0.085),
                                                    fingers=lambda width: nullcontext()))
    pairs = [Candidate(make_pose(t=[0.5, 0.01 * k, 0.02]), np.eye(4), np.eye(4)) for k in range(3)]
    in_table = lambda T, what: Blocked(f"the gripper at the {what} hits", ("rack", "table"))  # noqa: E731
    with pytest.raises(NoDemoLikeGrasp, match=f"^{NO_DEMO_LIKE_GRASP} exists in this pose"):
        choose(planner, pairs, np.zeros(6), np.array([0, 0, -1.0]), in_table)
    elsewhere = lambda T, what: Blocked("table at the place", ("table",)) if what == "place" else None  # noqa: E731
    with pytest.raises(NoCandidate, match="^none of 3 candidates could be planned") as raised:
        choose(planner, pairs, np.zeros(6), np.array([0, 0, -1.0]), elsewhere)
    assert not isinstance(raised.value, NoDemoLikeGrasp)  # the grasps are clear; the places are not


def test_a_job_that_looks_again_picks_a_reachable_grasp_whose_first_look_place_is_not():
    """With pick_only (the second look), pairs whose places all fail give the first grasp that plans
    alone, planned without a place; grasps that fail stay failures, and without pick_only it is a failure."""
    from contextlib import nullcontext
    from types import SimpleNamespace

    from app.failures import NoCandidate
    from app.jobs.choice import PICK_ONLY, choose
    from app.motion.ik import Blocked
    from app.predict.pairs import Candidate

    calls = []

    def pick_place(q, T_grasp, T_place, direction, widths):
        calls.append((T_grasp, T_place))
        return SimpleNamespace(T_base_grasp=T_grasp, T_base_place=T_place)

    planner = SimpleNamespace(scene=SimpleNamespace(geometry=SimpleNamespace(stroke=0.085),
                                                    fingers=lambda width: nullcontext()), pick_place=pick_place)
    pairs = [Candidate(make_pose(t=[0.5, 0.01 * k, 0.02]), np.eye(4), np.eye(4), grasp_rank=k) for k in range(3)]
    first_grasp_low = lambda T, what: (Blocked(f"the gripper at the {what} hits rack", ("rack",))  # noqa: E731
                                       if what == "place" or T[1, 3] < 0.005 else None)
    with pytest.raises(NoCandidate):
        choose(planner, pairs, np.zeros(6), np.array([0, 0, -1.0]), first_grasp_low)
    choice = choose(planner, pairs, np.zeros(6), np.array([0, 0, -1.0]), first_grasp_low, pick_only=True)
    assert choice.candidate.grasp_rank == 1 and calls == [(pairs[1].T_base_tcp, None)]
    assert [t["outcome"].endswith("(quick test)") for t in choice.tried] == [True, True, True, False]
    assert choice.tried[-1]["outcome"] == PICK_ONLY and choice.tried[-1]["grasp_rank"] == 1
    everything_low = lambda T, what: Blocked("the gripper at the grasp hits table", ("table",))  # noqa: E731
    with pytest.raises(NoCandidate):
        choose(planner, pairs, np.zeros(6), np.array([0, 0, -1.0]), everything_low, pick_only=True)


@pytest.mark.slow
def test_a_mug_hung_at_its_hang_drags_on_the_peg_only_when_bullet_thickens_the_hulls():
    """The oracle's mug of seed 5 placed at its hang (no clearance): at Bullet's default hull margin
    (1 mm) its handle's hole closes on the peg and the handle drags along the place line: the mug does
    not hang from the first place (let go off the rack, or dragging the arm into a stop); at the cell's 0.2 mm
    (`SimWorldConfig.mesh_margin`) the peg passes through and it hangs at the first place, as it does
    placed `MotionConfig.peg_clearance` (7 mm) above and dropped."""
    from app.motion.config import MotionConfig

    at_hang = JobConfig.of("teacher", motion=MotionConfig(peg_clearance=0.0))
    thick = replace(CellConfig(), world=replace(CellConfig().world, mesh_margin=0.001))
    dragged = _sim(JobSpec(task("mug"), seed=5), at_hang, config=thick)
    assert not (dragged.success and [a["outcome"] for a in dragged.attempts] == ["held"]), dragged.attempts
    result = _sim(JobSpec(task("mug"), seed=5), at_hang)
    assert result.success, result.reason
    assert [a["outcome"] for a in result.attempts] == ["held"]
    result = _sim(JobSpec(task("mug"), seed=5))
    assert result.success, result.reason


@pytest.mark.slow
def test_a_small_mug_is_approached_with_the_fingers_open_only_as_wide_as_the_rim_needs():
    """Mug seed 25 (scale 0.85): fully open (85 mm), the inner finger of the oracle's rim grasp would
    land on the mug's far wall: the quick test finds the seen wall in its way in and nothing is tried
    (unchecked, contact detection stopped the arm on every attempt); open to the held width +
    `approach_clearance` the arm comes down, closes on the rim and lifts the mug (whether it then hangs
    is the place's matter)."""
    spec = JobSpec(task("mug"), seed=25)
    wide = _sim(spec, JobConfig.of("teacher", approach_clearance=1.0))  # clipped to the stroke: fully open
    assert not wide.success and wide.failed_stage == "plan" and wide.attempts == []
    assert any("way in to the grasp passes through" in c["outcome"] for c in wide.candidates), wide.candidates
    result = _sim(spec)
    assert result.failed_stage not in ("approach", "grasp", "lift"), result.reason
    first = result.attempts[0]["outcome"]  # held through the carry: then hung, or missed at the place
    assert "carry" in result.seconds and (first == "held" or first.startswith("place")), result.attempts


def _series(seeds: list[int]) -> list[dict]:
    """The records of a series of NIFT mug jobs in one process, without their timings."""
    config = CellConfig()
    with SimCell(config) as cell:
        scene = PlanningScene(config)
        try:
            results = run_series(cell, scene, np.array(cell.camera.config.T_base_cam),
                                 [JobSpec(task("mug"), seed) for seed in seeds], JobConfig.of("nift"))
        finally:
            scene.close()
    records = [r.record() for r in results]
    for r in records:
        del r["seconds"], r["total_seconds"]
        r["plan"].pop("planning_seconds", None)  # no plan when a job fails before it
    return records


@pytest.mark.slow
def test_a_seed_gives_the_same_job_twice_in_one_process():
    """Open3D's back-projection returned a frame's points in a thread-timing order, and the grasp
    NIFT imitated on them followed it: seed 7 hung its mug, then, run again, jammed its release."""
    first, again = _series([7, 7])
    assert again == first  # the poses, the plan, the attempts, the second look, what the camera saw


def _down_line(arm, z_end: float, speed: float = 0.05):
    """A timed joint trajectory taking the TCP straight down from where it is to height z_end."""
    from app.motion.trajectory import JointTrajectory
    from hardware.se3 import ur_to_pose

    k = arm.robot.kinematics
    T0 = ur_to_pose(arm.getActualTCPPose())
    n = 60
    qs, q = [], arm.getActualQ()
    for s in np.linspace(0.0, 1.0, n):
        T = T0.copy()
        T[2, 3] += s * (z_end - T0[2, 3])
        q = k.ik(T, q)
        qs.append(q)
    times = np.linspace(0.0, abs(z_end - T0[2, 3]) / speed, n)
    return JointTrajectory(times, np.array(qs), np.gradient(np.array(qs), times, axis=0), "approach")


def test_an_approach_that_meets_something_within_7_mm_of_its_end_closes_there_and_one_farther_backs_off():
    """Straight down onto the bare table: the fingers touch it at some height; a line ending 4 mm past
    that has arrived (the job closes there and says so), one ending 30 mm past it backs off to its
    start and is a miss."""
    from types import SimpleNamespace

    from app.jobs.job import APPROACH_ARRIVED, GraspMissed, JobResult, _guarded_approach
    from hardware.se3 import ur_to_pose
    from hardware.sim.arm import SimArm, SimArmConfig
    from hardware.sim.robot import SimRobot
    from hardware.sim.world import SimWorld

    world = SimWorld()
    arm = SimArm(SimArmConfig(), SimRobot(world))
    with world, arm:
        job = SimpleNamespace(arm=arm, config=JobConfig(), kin=arm.robot.kinematics, result=JobResult("bowl", "nift"))
        start = arm.getActualQ()
        arm.startContactDetection(30.0)
        assert not arm.moveL(arm.getActualTCPPose() - [0, 0, 1.0, 0, 0, 0], 0.05)
        arm.stopContactDetection()
        z_touch = arm.getActualTCPPose()[2]
        assert arm.moveJ(start)
        short = _guarded_approach(job, _down_line(arm, z_touch - 0.004))
        assert 0.0 < short <= APPROACH_ARRIVED and "closed there" in job.result.notes[-1]
        assert not arm.isProtectiveStopped()
        assert arm.moveJ(start)
        with pytest.raises(GraspMissed, match="backed off to the pre-grasp"):
            _guarded_approach(job, _down_line(arm, z_touch - 0.03))
        assert np.abs(ur_to_pose(arm.getActualTCPPose())[:3, 3] - arm.robot.kinematics.fk(start)[:3, 3]).max() < 0.002
