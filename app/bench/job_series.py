"""`nift bench-jobs`: executed pick-and-place in the sim cell - success over a series of jobs per task,
with the failures counted by stage, and the cycle's figures (median and p90): the arm's seconds in
motion and joint travel, planning, imitation, decision and wall time."""
from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Callable

import numpy as np

from app.bench.memory import growth_across_refreshes, growth_mb_per_job, resident_mb
from app.failures import INTERNAL_ERROR, NoDemoLikeGrasp
from app.io_utils import write_json
from app.jobs.job import JobConfig, JobResult
from app.motion.scene import PlanningScene
from app.simcell.cell import CellConfig, SimCell
from app.simcell.sim_job import JobSpec, fresh_client_before, run_series
from app.tasks.task import task


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


def run_jobs_benchmark(jobs: int = 20, job: JobConfig = JobConfig(), pose: str = "upright", seed: int = 0,
                       tasks: tuple[str, ...] = ("mug", "bowl", "bottle"), cell_config: CellConfig = CellConfig(),
                       calibration: Path | None = None, progress: Callable[[JobResult], None] = lambda r: None,
                       records: Path | None = None, objects: dict[str, list] | None = None,
                       split: str = "test") -> dict:
    """Run `jobs` jobs per task (seeds seed .. seed + jobs - 1) and summarise them; the camera pose
    comes from the `calibration` file (calibrating first if it is missing), or is the true one;
    `records`: every job's record, as a JSON list, written there (atomically) at the end; `job`: how each
    job runs (its method, its second look, ...); `objects`: imported objects by category, each run `jobs`
    times (seeds seed .. seed + jobs - 1) instead of procedural ones, which come from `split`."""
    from app.simcell.calibration import ensure_calibration

    figures: dict = {"method": job.method, "pose": pose, "jobs_per_task": jobs}
    if objects is not None:
        figures = {**figures, "jobs_per_object": jobs, "objects": {c: [o.name for o in v] for c, v in objects.items()}}
        del figures["jobs_per_task"]
    elif split != "test":
        figures["split"] = split
    every: list[dict] = []
    rss: list[float] = []  # MiB after each job

    def each(result: JobResult) -> None:
        rss.append(resident_mb())
        progress(result)

    with SimCell(cell_config) as cell:
        T_cam = np.array(cell.camera.config.T_base_cam) if calibration is None else ensure_calibration(cell, calibration)
        scene = PlanningScene(cell_config)
        try:
            for name in tasks:
                t = task(name)
                if objects is None:
                    specs = [JobSpec(t, seed + i, pose, split=split) for i in range(jobs)]
                else:
                    specs = [JobSpec(t, seed + i, pose, o) for o in objects[t.category] for i in range(jobs)]
                results = run_series(cell, scene, T_cam, specs, job, each)
                figures.update(summarise(name, results))
                if objects is not None:
                    figures[f"{name}_per_object"] = per_object(results)
                every += [r.record() for r in results]
        finally:
            scene.close()
    if records is not None:
        write_json(records, every)
    figures.update({"resident_mb_after_first_job": round(rss[0], 1), "resident_mb_after_last_job": round(rss[-1], 1),
                    "resident_mb_max": round(max(rss), 1),
                    "resident_mb_growth_per_job_second_half": round(growth_mb_per_job(rss), 3)})
    fresh = [0] + [k * jobs + i for k in range(len(tasks)) for i in range(jobs) if fresh_client_before(i)]
    if (kept := growth_across_refreshes(rss, fresh)) is not None:
        figures["resident_mb_growth_per_job_across_refreshes"] = round(kept, 3)
    figures["resident_mb_every_20_jobs"] = {i: round(rss[i], 1) for i in range(0, len(rss), 20)}  # job index -> MiB
    return figures
