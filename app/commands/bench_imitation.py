"""`nift bench-imitation`: seconds per prediction and pose errors against the scripted teacher."""
from __future__ import annotations

import argparse

from app.commands.output import print_figures

NAME = "bench-imitation"
HELP = "measure imitation time per prediction and grasp/place errors on unseen test objects"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from app.methods import METHODS
    from app.nift.imitation_config import ImitationConfig

    p.add_argument("--method", default="nift", choices=METHODS, help="method to measure (default nift)")
    p.add_argument("--objects", type=int, default=20, help="test objects per task (default 20)")
    p.add_argument("--tasks", default="mug,bowl,bottle", help="comma list of tasks")
    p.add_argument("--quick", action="store_true", help="two objects per task (CI size)")
    p.add_argument("--seed", type=int, default=0, help="objects, poses, scales, initialisations")
    p.add_argument("--prune-every", type=int, default=ImitationConfig.prune_every,
                   help="drop the worse half of the initialisations every N steps (0: the paper's, no pruning)")
    p.add_argument("--iterations", type=int, default=ImitationConfig.iterations,
                   help="iteration budget per template (the step size decays over it)")
    p.add_argument("--patience", type=int, default=ImitationConfig.patience,
                   help="stop when no initialisation improved for this many steps")
    p.add_argument("--explore-points", type=int, default=ImitationConfig.explore_points,
                   help="template points the loss uses while pruning (0: all)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")


def run(args: argparse.Namespace) -> int:
    from app.bench.imitation import run_imitation_benchmark
    from app.nift.imitation_config import ImitationConfig

    tasks = tuple(t.strip() for t in args.tasks.split(",") if t.strip())
    config = ImitationConfig(iterations=args.iterations, patience=args.patience, prune_every=args.prune_every,
                             explore_points=args.explore_points)
    figures = run_imitation_benchmark(args.quick, args.seed, args.method, args.objects, tasks, config)
    print_figures(figures, args.json, {f"{t}_seconds_per_template": "<= 2" for t in tasks})
    return 0
