"""`nift make-data`: generate field training data (clouds, query points, SCF and occupancy labels)."""
from __future__ import annotations

import argparse
from pathlib import Path

from app.categories import SPLIT_NAMES
from app.console.options import add_cluster_arguments
from app.console.output import print_figures

NAME = "make-data"
HELP = "generate sharded, resumable field training data from procedural objects"
QUICK = {"instances": 3, "views": 2, "queries": 300, "shard_instances": 3}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", type=Path, required=True, help="data directory (resumes if it holds a manifest)")
    p.add_argument("--split", default="train", choices=SPLIT_NAMES,
                   help="instance seeds to draw from (wide-train: every family not held out; docs/objects.md)")
    p.add_argument("--categories", default="mug,bowl,bottle", help="comma list (vase stays out of training)")
    p.add_argument("--instances", type=int, default=500, help="instances per category (default 500)")
    p.add_argument("--views", type=int, default=8, help="samples (scale, pose, camera view) per instance")
    p.add_argument("--camera", default="single", choices=["single", "fused"],
                   help="one Kinect (our cell) or four fused corner cameras (the paper's setting)")
    p.add_argument("--points", type=int, default=1024, help="points per cloud")
    p.add_argument("--queries", type=int, default=2000, help="labelled query points per instance")
    p.add_argument("--scf-order", type=int, default=10, help="highest SCF band stored (fields use 0..n)")
    add_cluster_arguments(p, "shards")
    p.add_argument("--seed", type=int, default=0, help="picks instances, poses, scales and views")
    p.add_argument("--quick", action="store_true", help="a tiny dataset (CI size)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")


def config_from(args: argparse.Namespace):
    """The DataConfig the arguments describe."""
    from app.training.data import DataConfig

    values = dict(split=args.split, categories=tuple(c.strip() for c in args.categories.split(",") if c.strip()),
                  instances=args.instances, views=args.views, camera=args.camera, points=args.points,
                  queries=args.queries, scf_order=args.scf_order, seed=args.seed)
    if args.quick:
        values.update(QUICK)
    return DataConfig(**values)


def run(args: argparse.Namespace) -> int:
    from app.console.options import cluster_of
    from app.fanout.cluster import warmed

    with warmed(cluster_of(args)) as cluster:  # checked before anything is written; Ray starts while modules load
        from app.training.data import make_dataset

        report = make_dataset(config_from(args), args.out, workers=cluster, progress=not args.json)
    print_figures(report.figures(), args.json)
    return 1 if report.failed else 0
