"""The job's motion meter (app.jobs.motion_meter): seconds on the controller's clock and joint travel,
on the fake arm, whose clock advances by each motion's nominal duration."""
import numpy as np
import pytest

from app.jobs.motion_meter import MeteredArm, path_travel
from hardware.fake import FakeArm, Interruption


def test_path_travel_sums_the_joint_distance_up_to_where_the_arm_stopped():
    path = np.zeros((3, 6))
    path[1, 0], path[2, 0], path[2, 1] = 1.0, 1.0, 2.0  # 1 rad on joint 0, then 2 rad on joint 1
    assert path_travel(path, path[2]) == pytest.approx(3.0)
    assert path_travel(path, path[1]) == pytest.approx(1.0)
    stopped = path[1] + [0.0, 0.5, 0, 0, 0, 0]  # halfway along the second leg: nearest sample is path[1]
    assert path_travel(path, stopped) == pytest.approx(1.5)


@pytest.fixture
def arm():
    a = FakeArm()
    a.connect()
    yield a
    a.disconnect()


def trajectory(q0: np.ndarray, seconds: float = 2.0, k: int = 31) -> tuple[np.ndarray, np.ndarray]:
    """(times (k,), q (k, 6)): joint 0 swept by 1 rad and back by 0.5 rad over `seconds` (the turn a sample)."""
    s = np.linspace(0.0, 1.0, k)
    q = np.tile(q0, (k, 1))
    q[:, 0] += np.where(s <= 2 / 3, 1.5 * s, 1.0 - 1.5 * (s - 2 / 3))
    return s * seconds, q


def test_a_trajectory_counts_its_duration_and_its_travel_back_and_forth(arm):
    meter = MeteredArm(arm)
    times, q = trajectory(arm.getActualQ())
    assert meter.executeTrajectory(times, q)
    assert meter.seconds == pytest.approx(2.0) and meter.travel == pytest.approx(1.5)  # not the 0.5 rad net


def test_a_stopped_motion_counts_as_far_as_it_got(arm):
    arm.interruptions.append(Interruption(lambda m: True, at=0.5, contact=False))
    meter = MeteredArm(arm)
    q = arm.getActualQ() + [0.0, 0.0, 0.8, 0.0, 0.0, 0.4]
    assert not meter.moveJ(q, speed=0.4)
    assert meter.seconds == pytest.approx(0.5 * 0.8 / 0.4)
    assert meter.travel == pytest.approx(0.5 * 1.2)


def test_other_verbs_pass_through_uncounted(arm):
    meter = MeteredArm(arm)
    np.testing.assert_array_equal(meter.getActualQ(), arm.getActualQ())
    meter.stopJ()
    assert arm.stops == 1 and meter.seconds == 0.0 and meter.travel == 0.0


def test_bench_jobs_reports_the_median_and_p90_of_each_jobs_motion():
    from app.bench.job_series import timings
    from app.jobs.record import JobResult

    results = []
    for k, moved in enumerate((2.0, 4.0)):
        r = JobResult("bowl", "nift", success=True, seconds={"capture": 0.1, "imitate": 0.5 * moved, "carry": 1.0},
                      plan={"planning_seconds": 0.1 * moved, "trajectory_seconds": 5.0})
        r.motion = {"motion_seconds": moved, "joint_travel_rad": 3 * moved}
        results.append(r)
    t = timings("bowl", results)
    assert t["bowl_motion_seconds"] == {"median": 3.0, "p90": 3.8}
    assert t["bowl_joint_travel_rad"] == {"median": 9.0, "p90": 11.4}
    assert t["bowl_imitate_seconds"] == {"median": 1.5, "p90": 1.9}
    assert t["bowl_decide_seconds"] == t["bowl_imitate_seconds"]  # no perceive or plan stage in these records
    assert t["bowl_job_seconds"] == {"median": 2.6, "p90": 3.0}
    assert t["bowl_planning_seconds"] == {"median": 0.3, "p90": 0.38}


def test_each_motion_counts_to_the_stage_it_ran_in_and_the_stages_sum_to_the_whole(arm):
    meter = MeteredArm(arm)
    q0 = arm.getActualQ()
    meter.stage = "approach"
    assert meter.moveJ(q0 + [0.4, 0, 0, 0, 0, 0], speed=0.4)  # 1 s, 0.4 rad
    meter.stage = "carry"
    times, q = trajectory(arm.getActualQ())
    assert meter.executeTrajectory(times, q)  # 2 s, 1.5 rad
    assert meter.moveJ(q0, speed=0.5)
    by = meter.record()["by_stage"]
    assert list(by) == ["approach", "carry"]
    assert by["approach"] == {"motion_seconds": pytest.approx(1.0), "joint_travel_rad": pytest.approx(0.4)}
    assert by["carry"]["motion_seconds"] == pytest.approx(2.0 + 0.9 / 0.5)
    assert sum(s["motion_seconds"] for s in by.values()) == pytest.approx(meter.seconds)
    assert sum(s["joint_travel_rad"] for s in by.values()) == pytest.approx(meter.travel)
