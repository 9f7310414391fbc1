"""`nift bench`: the paper's success-rate tables, reproducible with one command (docs/benchmark.md)."""
from __future__ import annotations

import argparse
import shutil
from pathlib import Path

NAME = "bench"
HELP = "success rates of NIFT and the baselines on unseen objects (paper Tables I and II), resumable"

QUICK = {"trials": 2, "methods": "cpd,ibs-nif", "poses": "upright"}


def add_arguments(p: argparse.ArgumentParser) -> None:
    from app.console.options import add_cluster_arguments
    from app.nift.imitation_config import DEMO_MATCHES, ImitationConfig

    p.add_argument("--tasks", default="mug,bowl,bottle",
                   help="comma list: mug, bowl, bottle, and the out-of-domain bowl-demos-on-mug, bottle-demos-on-vase")
    p.add_argument("--poses", default="upright,arbitrary", help="comma list: upright, arbitrary")
    p.add_argument("--methods", default="cpd,bps-ndf,bps-scf,bps-nif,ibs-ndf,ibs-scf,ibs-nif",
                   help="comma list of methods (nift = ibs-nif; oracle, alias teacher: the simulator's true poses)")
    p.add_argument("--trials", type=int, default=100, help="objects per task and pose (paper: 100)")
    p.add_argument("--demos", type=int, default=10, help="demos per task, the first N of demos/<task> (paper: 10)")
    p.add_argument("--camera", default="single", choices=["single", "fused"],
                   help="single: the cell's Kinect; fused: four cameras around the object (the paper's setting)")
    p.add_argument("--setting", default="teleported", choices=["teleported", "executed"],
                   help="teleported: the paper's judges; executed: whole jobs through IK, trajectories and the gripper")
    p.add_argument("--seed", type=int, default=0, help="the run's seed (objects, poses, noise, initialisations)")
    p.add_argument("--fields", "--nif", dest="nif", metavar="PATH",
                   help="other field weights: a NIF .pt for the nif and scf rows (Table III), or a directory with "
                        "nif.pt and ndf.pt for every template row (default: the shipped fields; with --camera fused "
                        "the fields trained on fused clouds, app/nift/weights/fused)")
    p.add_argument("--no-centering", "--no-center-grasp", dest="center_grasp", action="store_false",
                   help="judge the methods' poses as predicted: grasps not centred between the fingers, "
                        "hangs not centred on the peg (docs/additions.md)")
    p.add_argument("--align-grasp", action=argparse.BooleanOptionalAction, default=None,
                   help="turn every method's grasp so the fingers close along the normal of the wall between them "
                        "(default: with --camera fused only; docs/additions.md)")
    p.add_argument("--no-feasibility", dest="feasible", action="store_false",
                   help="take each template method's lowest-loss poses even where the fingers would close on "
                        "nothing or the place turns the object over relative to the grasp (docs/additions.md)")
    p.add_argument("--place-contact-scale", type=float, default=ImitationConfig.place_contact_scale,
                   help="metres: weight place template points by exp(-d / scale), d their distance to the rack or "
                        f"shelf (default {ImitationConfig.place_contact_scale}; 0: the paper's plain mean; docs/additions.md)")
    p.add_argument("--place-demo-match", choices=DEMO_MATCHES, default=ImitationConfig.place_demo_match,
                   help="compare a place pose with the demos' mean features (mean, the paper's) or with each demo's "
                        f"own, taking the nearest (nearest); default {ImitationConfig.place_demo_match} (docs/additions.md)")
    p.add_argument("--objects", metavar="NAMES", help="comma list of imported objects (nift objects import) to use "
                   "instead of procedural ones; each task's trials cycle over those of its category")
    p.add_argument("--demo-dir", type=Path, metavar="DIR",
                   help="the directory whose <task>/ folders hold the demos (default: the project's demos/)")
    add_cluster_arguments(p, "trials")
    p.add_argument("--minutes", type=float,
                   help="stop after this wall time and write the table of the trials done (the same command resumes)")
    p.add_argument("--out", type=Path, default=Path("out/bench"), help="results directory (resumes a run there)")
    p.add_argument("--quick", action="store_true", help="CI size: 2 trials, cpd and ibs-nif, upright only")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")


def _names(text: str) -> tuple[str, ...]:
    return tuple(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))


def run(args: argparse.Namespace) -> int:
    import json

    from tqdm import tqdm

    from app.bench.protocol import BenchConfig
    from app.bench.report import write_report
    from app.bench.runner import run as run_bench
    from app.console.options import cluster_of
    from app.io_utils import writable_directory
    from app.nift.field import load_field
    from app.nift.template import field_override
    from app.predict.methods import canonical
    from app.categories import POSES
    from app.tasks.task import task

    if args.quick:
        args.trials, args.methods, args.poses = QUICK["trials"], QUICK["methods"], QUICK["poses"]
    tasks = tuple(task(t).name for t in _names(args.tasks))
    poses = _names(args.poses)
    for pose in poses:
        if pose not in POSES:
            raise ValueError(f"unknown pose setting {pose!r}; choose from {', '.join(POSES)}")
    methods = tuple(canonical(m) for m in _names(args.methods))
    config = BenchConfig(tasks, poses, methods, args.trials, args.demos, args.camera, args.setting, args.seed,
                         args.nif, center_grasp=args.center_grasp, align_grasp=args.align_grasp,
                         feasible=args.feasible,
                         place_contact_scale=args.place_contact_scale, place_demo_match=args.place_demo_match,
                         objects=_names(args.objects or ""),
                         demo_dir=str(args.demo_dir.resolve()) if args.demo_dir else None)
    config.check()  # before the progress bar: the error is the only line
    cluster = cluster_of(args)
    writable_directory(args.out, "--out")
    if args.nif is not None:  # the weights load before any work (and before the bar)
        for feature in ("nif", "ndf"):
            if (weights := field_override(feature, args.nif)) is not None:
                load_field(weights)
    created = not args.out.exists()
    try:
        with tqdm(unit="trial", desc="bench", disable=args.json) as bar:
            def progress(done: int, total: int, failed: int) -> None:
                bar.total, bar.n = total, done
                bar.set_postfix(failed=failed, refresh=False)
                bar.refresh()

            rows = run_bench(config, args.out, cluster, progress, args.minutes)
    except BaseException:
        if created and not (args.out / "results.jsonl").exists():  # a failed start leaves no half-made folder
            shutil.rmtree(args.out, ignore_errors=True)
        raise
    title = f"{args.setting} setting, {args.camera} camera, {args.demos} demos, seed {args.seed}"
    if config.fields:
        title += f", fields {config.fields}"
    summary = write_report(rows, list(tasks), list(poses), list(methods), args.out, title)
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print((args.out / "table.md").read_text())
        done = len({r["trial"] for r in rows})
        if done < len(tasks) * len(poses) * args.trials:
            print(f"stopped after {args.minutes} minutes: {done} of {len(tasks) * len(poses) * args.trials} trials; "
                  "the same command resumes")
        print(f"written: {args.out / 'table.md'}, {args.out / 'summary.json'}, {args.out / 'chart.png'}, "
              f"{args.out / 'results.jsonl'}")
    return 0
