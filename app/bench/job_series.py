"""`nift bench-jobs`: executed pick-and-place in the sim cell - success over a series of jobs per task,
with the failures counted by stage, and the cycle's figures (median and p90): the arm's seconds in
motion and joint travel, planning, imitation, decision and wall time.

The jobs are Ray tasks (app.fanout): each worker builds its own cell and planning scene, refreshes
their physics clients every REFRESH_EVERY jobs as a series in one process does, and is replaced by a
fresh process after RECYCLE_AFTER jobs. A job's record is a function of its spec (the object, pose and
camera noise all follow from its seed), so the rows do not depend on the number of workers.
"""
from __future__ import annotations

import os
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from app.bench.memory import growth_across_refreshes, growth_mb_per_job, resident_mb
from app.fanout.cluster import ClusterConfig
from app.fanout.run import fan_out
from app.failures import INTERNAL_ERROR, NoDemoLikeGrasp
from app.io_utils import write_json
from app.jobs.job import JobConfig, JobResult
from app.motion.scene import PlanningScene
from app.simcell.cell import CellConfig, SimCell
from app.simcell.sim_job import JobSpec, fresh_client_before, run_sim_job
from app.tasks.task import task

RECYCLE_AFTER = 100  # jobs a worker process runs before a fresh one replaces it


def _moved_place(look: dict) -> bool:
    """Whether the second look chose the place: moved the first plan's by over 1 cm, or gave a pick alone one."""
    return bool(look.get("used")) and (bool(look.get("pick_only")) or look.get("place_moved_m", 0.0) > 0.01)


DECIDING = ("perceive", "imitate", "plan")  # the stages between the first picture and the arm's first motion


def spread(values: list[float], digits: int = 2) -> dict[str, float] | None:
    """{"median", "p90"} of the values (None when there are none)."""
    if not values:
        return None
    return {"median": round(float(np.median(values)), digits), "p90": round(float(np.percentile(values, 90)), digits)}


def timings(name: str, results: list[JobResult]) -> dict:
    """The cycle's figures of one task's series, median and p90 over its jobs: the arm's seconds in
    motion and its joint travel (`app.jobs.motion_meter`), the chosen plan's planning time, the
    imitation stage, the decision (perceive, imitate and plan stages) and the job's wall time."""
    moved = [r.motion for r in results if r.motion]
    return {
        f"{name}_motion_seconds": spread([m["motion_seconds"] for m in moved]),
        f"{name}_joint_travel_rad": spread([m["joint_travel_rad"] for m in moved]),
        f"{name}_planning_seconds": spread([r.plan["planning_seconds"] for r in results if r.plan], 3),
        f"{name}_imitate_seconds": spread([r.seconds["imitate"] for r in results if "imitate" in r.seconds]),
        f"{name}_decide_seconds": spread([sum(r.seconds.get(s, 0.0) for s in DECIDING) for r in results]),
        f"{name}_job_seconds": spread([sum(r.seconds.values()) for r in results]),
    }


def summarise(name: str, results: list[JobResult]) -> dict:
    """Figures of one task's series."""
    failed = [r for r in results if not r.success and r.failure_kind != INTERNAL_ERROR]  # the cell's failures
    no_grasp = sum(r.failure_kind == NoDemoLikeGrasp.kind for r in results)
    bugs = sum(r.failure_kind == INTERNAL_ERROR for r in results)
    possible = len(results) - no_grasp
    out = {
        f"{name}_success": f"{sum(r.success for r in results)}/{len(results)}",
        f"{name}_success_rate": round(float(np.mean([r.success for r in results])), 3),
        f"{name}_mean_attempts": round(float(np.mean([max(1, len(r.attempts)) for r in results])), 2),
        f"{name}_no_demo_like_grasp": no_grasp,  # jobs where no grasp like the demos' exists in the pose
        f"{name}_success_where_a_demo_like_grasp_exists":
            round(sum(r.success for r in results) / possible, 3) if possible else None,
    }
    out.update(timings(name, results))
    looked = [r.look for r in results if r.look]
    if looked:
        out[f"{name}_second_look_used"] = sum(bool(k.get("used")) for k in looked)
        out[f"{name}_second_look_moved_place"] = sum(_moved_place(k) for k in looked)
        out[f"{name}_picked_before_a_place"] = sum(bool(k.get("pick_only")) for k in looked)
    out[f"{name}_failures"] = dict(sorted(Counter(r.failed_stage for r in failed).items())) or "none"
    out[f"{name}_failure_kinds"] = dict(sorted(Counter(r.failure_kind for r in failed).items())) or "none"
    out[f"{name}_internal_errors"] = bugs  # bugs of ours, not failures of the cell: counted apart
    return out


def per_object(results: list[JobResult]) -> dict[str, str]:
    """Successes per imported object: name -> "k/n"."""
    tally: dict[str, list[bool]] = {}
    for r in results:
        tally.setdefault(r.info.get("object", "?"), []).append(r.success)
    return {name: f"{sum(v)}/{len(v)}" for name, v in tally.items()}


@dataclass(frozen=True)
class SeriesSetup:
    """What every worker of a series needs: the cell's settings, the calibrated camera pose, how jobs run."""

    cell: CellConfig
    T_base_cam: np.ndarray
    job: JobConfig
    rerun: Path | None = None  # a folder: each job's recording written there (`recording_name`)


@dataclass
class CellWorker:
    """A worker process's own simulated cell and planning scene, and how many jobs it has run."""

    cell: SimCell
    scene: PlanningScene
    setup: SeriesSetup
    jobs: int = 0

    def close(self) -> None:
        self.scene.close()
        self.cell.disconnect()


@dataclass(frozen=True)
class JobRun:
    """One job's result, with the worker's memory after it (MiB), which worker ran it and its job count there."""

    result: JobResult
    resident_mb: float
    worker: int
    number: int


def make_cell_worker(setup: SeriesSetup) -> CellWorker:
    cell = SimCell(setup.cell)
    cell.connect()
    return CellWorker(cell, PlanningScene(setup.cell), setup)


def run_spec(worker: CellWorker, spec: JobSpec) -> JobRun:
    """One job in this worker's cell (on fresh physics clients every REFRESH_EVERY jobs)."""
    if fresh_client_before(worker.jobs):
        worker.cell.refresh()
        worker.scene.rebuild()
    job_log = None
    if worker.setup.rerun is not None:
        from app.recording.target import open_log

        job_log = open_log(worker.setup.rerun / recording_name(spec), recording_name(spec).removesuffix(".rrd"))
    result = run_sim_job(worker.cell, worker.scene, worker.setup.T_base_cam, spec, worker.setup.job, job_log=job_log)
    worker.jobs += 1
    return JobRun(result, resident_mb(), os.getpid(), worker.jobs - 1)


def recording_name(spec: JobSpec) -> str:
    """The file of a job's recording in a `--rerun` folder: task, object (if imported), pose and seed."""
    what = spec.task.name if spec.source is None else f"{spec.task.name}-{spec.source.name}"
    return f"{what}-{spec.pose}-{spec.seed:04d}.rrd"


def recordings_index(specs: list[JobSpec], results: list[JobResult]) -> dict:
    """The `--rerun` folder's index: every job's recording and outcome, and the failed ones by stage."""
    jobs = [{"file": recording_name(s), "task": s.task.name, "seed": s.seed, "success": r.success,
             "failed_stage": r.failed_stage, "failure_kind": r.failure_kind, "reason": r.reason}
            for s, r in zip(specs, results)]
    by_stage: dict[str, list[str]] = {}
    for j in jobs:
        if not j["success"]:
            by_stage.setdefault(j["failed_stage"] or "verdict", []).append(j["file"])
    return {"jobs": jobs, "failures_by_stage": by_stage}


def failed_job(spec: JobSpec, job: JobConfig, error: str) -> JobRun:
    """A job whose task raised outside the job's own handling: an internal error in its record."""
    result = JobResult(spec.task.name, job.method, reason=f"internal error: {error}", failure_kind=INTERNAL_ERROR)
    result.info = {"seed": spec.seed, "pose": spec.pose}
    return JobRun(result, float("nan"), -1, -1)


def camera_pose(cell_config: CellConfig, calibration: Path | None) -> np.ndarray:
    """T_base_cam from the calibration file (calibrating a cell here first if it is missing), or the true one."""
    from app.simcell.calibration import ensure_calibration, load_calibration

    if calibration is not None and calibration.exists():
        return load_calibration(calibration)[0]
    with SimCell(cell_config) as cell:
        return np.array(cell.camera.config.T_base_cam) if calibration is None else ensure_calibration(cell, calibration)


def memory_figures(runs: list[JobRun]) -> dict:
    """Resident memory per worker: after its first and last job, the peak, and its growth per job
    (second half; across fresh physics clients), the worst worker's."""
    by_worker: dict[int, list[JobRun]] = {}
    for r in runs:
        if r.worker >= 0:
            by_worker.setdefault(r.worker, []).append(r)
    if not by_worker:
        return {}
    series = [[r.resident_mb for r in sorted(v, key=lambda r: r.number)] for v in by_worker.values()]
    longest = max(series, key=len)
    figures = {"workers_used": len(series), "resident_mb_after_first_job": round(longest[0], 1),
               "resident_mb_after_last_job": round(longest[-1], 1),
               "resident_mb_max": round(max(max(s) for s in series), 1),
               "resident_mb_growth_per_job_second_half": round(max(growth_mb_per_job(s) for s in series), 3)}
    kept = [g for s in series if (g := growth_across_refreshes(s, [0] + [i for i in range(len(s))
                                                                       if fresh_client_before(i)])) is not None]
    if kept:
        figures["resident_mb_growth_per_job_across_refreshes"] = round(max(kept), 3)
    figures["resident_mb_every_20_jobs"] = {i: round(longest[i], 1) for i in range(0, len(longest), 20)}
    return figures


def run_jobs_benchmark(jobs: int = 20, job: JobConfig = JobConfig(), pose: str = "upright", seed: int = 0,
                       tasks: tuple[str, ...] = ("mug", "bowl", "bottle"), cell_config: CellConfig = CellConfig(),
                       calibration: Path | None = None, progress: Callable[[JobResult], None] = lambda r: None,
                       records: Path | None = None, objects: dict[str, list] | None = None,
                       split: str = "test", cluster: ClusterConfig = ClusterConfig(1),
                       rerun: Path | None = None) -> dict:
    """Run `jobs` jobs per task (seeds seed .. seed + jobs - 1) and summarise them; the camera pose
    comes from the `calibration` file (calibrating first if it is missing), or is the true one;
    `records`: every job's record, as a JSON list in the specs' order, written there (atomically) at the
    end; `job`: how each job runs (its method, its second look, ...); `objects`: imported objects by
    category, each run `jobs` times (seeds seed .. seed + jobs - 1) instead of procedural ones, which
    come from `split`; `cluster`: where the jobs run (app.fanout; one worker: here, in order); `rerun`: a
    folder for each job's Rerun recording and their index (`index.json`, failures by stage)."""
    figures: dict = {"method": job.method, "pose": pose, "jobs_per_task": jobs}
    if objects is not None:
        figures = {**figures, "jobs_per_object": jobs, "objects": {c: [o.name for o in v] for c, v in objects.items()}}
        del figures["jobs_per_task"]
    elif split != "test":
        figures["split"] = split
    specs: list[JobSpec] = []
    for name in tasks:
        t = task(name)
        if objects is None:
            specs += [JobSpec(t, seed + i, pose, split=split) for i in range(jobs)]
        else:
            specs += [JobSpec(t, seed + i, pose, o) for o in objects[t.category] for i in range(jobs)]
    setup = SeriesSetup(cell_config, camera_pose(cell_config, calibration), job, rerun)
    runs: list[JobRun | None] = [None] * len(specs)
    for outcome in fan_out(run_spec, specs, make_cell_worker, setup, cluster, RECYCLE_AFTER):
        spec = specs[outcome.index]
        runs[outcome.index] = failed_job(spec, job, outcome.error) if outcome.failed else outcome.value
        progress(runs[outcome.index].result)
    every = []
    for name in tasks:
        results = [r.result for r, s in zip(runs, specs) if s.task.name == name]
        figures.update(summarise(name, results))
        if objects is not None:
            figures[f"{name}_per_object"] = per_object(results)
        every += [r.record() for r in results]
    if records is not None:
        write_json(records, every)
    if rerun is not None:
        write_json(rerun / "index.json", recordings_index(specs, [r.result for r in runs]))
        figures["recordings"] = str(rerun)
    figures.update(memory_figures(runs))
    return figures
