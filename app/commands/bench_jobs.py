"""`nift bench-jobs`: executed pick-and-place success, planning and job times per task."""
from __future__ import annotations

import argparse
from pathlib import Path

from app.categories import POSES
from app.console.options import (add_cluster_arguments, add_config_argument, add_job_config_argument,
                                 add_second_look_argument)
from app.console.output import print_figures

NAME = "bench-jobs"
HELP = "run a series of executed jobs per task and report success, planning, trajectory and job times"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from app.predict.methods import choices

    p.add_argument("--method", choices=choices(), help="method (default nift; oracle, alias teacher: the simulator's "
                   "true poses)")
    p.add_argument("--jobs", type=int, default=20, help="jobs per task (default 20); with --objects, per object")
    p.add_argument("--objects", metavar="SET", help="run on imported objects instead of procedural ones: a set file "
                   "(e.g. shapes/real/set.toml; imported first where missing) or a comma list of library names")
    p.add_argument("--split", default="test", choices=("test", "wide-test"),
                   help="procedural objects' split (wide-test: every family, held-out ones included)")
    p.add_argument("--tasks", default="mug,bowl,bottle", help="comma list of tasks")
    p.add_argument("--pose", default="upright", choices=POSES, help="how the objects stand (see nift run --help)")
    p.add_argument("--quick", action="store_true", help="two jobs per task (CI size)")
    p.add_argument("--seed", type=int, default=0, help="first job's seed")
    p.add_argument("--calibration", type=Path, default=Path("calibration.json"),
                   help="camera calibration file; if missing, the cell is calibrated first and it is written")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--records", type=Path, default=None, help="also write every job's record (a JSON list) to this file")
    p.add_argument("--rerun", metavar="DIR", help="write every job's Rerun recording to DIR, with index.json: the "
                                                   "failed jobs by stage (docs/recording.md)")
    add_cluster_arguments(p, "jobs", 1, "one job at a time, so the timings are a cell's own")
    add_second_look_argument(p)
    add_config_argument(p)
    add_job_config_argument(p)


def run(args: argparse.Namespace) -> int:
    from app.console.options import cell_config, cluster_of, job_config
    from app.io_utils import writable_file
    from app.tasks.task import task

    tasks = tuple(task(t.strip()).name for t in args.tasks.split(",") if t.strip())
    jobs = 2 if args.quick else args.jobs
    if jobs < 1:
        raise ValueError(f"--jobs must be at least 1, got {jobs}")
    cell_cfg = cell_config(args)  # a bad --config or --job-config fails before the progress bar
    job = job_config(args)
    cluster = cluster_of(args)
    if args.records is not None:
        writable_file(args.records, "--records")
    rerun = None
    if args.rerun is not None:
        from app.recording.target import check_target

        rerun = check_target(args.rerun, "--rerun", folder=True)
    objects = None
    if args.objects is not None:
        from app.objects.shape_set import named_objects

        objects = named_objects(args.objects)
        tasks = tuple(t for t in tasks if task(t).category in objects)
        if not tasks:
            raise ValueError(f"--objects {args.objects}: no object of the tasks' categories")
    per_task = {t: jobs * len(objects[task(t).category]) if objects else jobs for t in tasks}

    from tqdm import tqdm

    from app.bench.job_series import run_jobs_benchmark

    failed = 0

    def progress(result) -> None:
        nonlocal failed
        failed += not result.success
        bar.set_postfix(failed=failed, refresh=False)
        bar.update(1)

    with tqdm(total=sum(per_task.values()), unit="job", desc="bench-jobs", disable=args.json) as bar:
        figures = run_jobs_benchmark(jobs, job, args.pose, args.seed, tasks, cell_cfg, args.calibration,
                                     progress, args.records, objects, args.split, cluster, rerun)
    print_figures(figures, args.json)
    return 0
