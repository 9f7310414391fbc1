"""`nift bench-imitation`: seconds per prediction and pose errors against the scripted teacher."""
from __future__ import annotations

import argparse

from app.console.output import print_figures

NAME = "bench-imitation"
HELP = "measure imitation time per prediction and grasp/place errors on unseen test objects"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from app.console.options import add_cluster_arguments, add_imitation_arguments
    from app.predict.methods import choices

    p.add_argument("--method", default="nift", choices=choices(true_poses=False),
                   help="method to measure (default nift)")
    p.add_argument("--objects", type=int, default=20, help="test objects per task (default 20)")
    p.add_argument("--tasks", default="mug,bowl,bottle", help="comma list of tasks")
    p.add_argument("--quick", action="store_true", help="two objects per task (CI size)")
    p.add_argument("--seed", type=int, default=0, help="objects, poses, scales, initialisations")
    p.add_argument("--schedule", choices=("teleported", "cell"), default="teleported",
                   help="teleported: the paper tables' optimiser (the options below); cell: a job's whole prediction, "
                        "its schedule and refinements (configs/job.toml's [predict])")
    p.add_argument("--busy", type=int, default=0,
                   help="run this many busy processes beside the benchmark (a loaded cell PC; default 0)")
    add_cluster_arguments(p, "predictions", 1, "one at a time, so the seconds are a cell's; more: one torch thread each")
    add_imitation_arguments(p)
    p.add_argument("--json", action="store_true", help="print the figures as JSON")


def run(args: argparse.Namespace) -> int:
    from app.console.options import cluster_of, imitation_config

    tasks = tuple(t.strip() for t in args.tasks.split(",") if t.strip())
    config = imitation_config(args)  # bad options fail here, before the benchmark's imports (torch: seconds)
    if not 0 <= args.busy <= 64:
        raise ValueError(f"--busy must be in [0, 64] processes, got {args.busy}")
    cluster = cluster_of(args)

    from app.bench.busy import busy_processes
    from app.bench.imitation import run_imitation_benchmark

    with busy_processes(args.busy):
        figures = run_imitation_benchmark(args.quick, args.seed, args.method, args.objects, tasks, config,
                                          args.schedule, cluster)
    figures["busy_processes"] = args.busy
    print_figures(figures, args.json, {f"{t}_seconds_per_prediction": "<= 0.5 alone, <= 1 beside one busy process"
                                       for t in tasks} if args.schedule == "cell" else {})
    return 1 if figures.get("errors") else 0
