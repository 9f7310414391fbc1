"""Options several verbs share: the cell's --config (a TOML CellConfig, camera seeded by --seed) and
the optimiser options of `nift imitate` and `nift bench-imitation`, with ImitationConfig's defaults."""
from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path


def add_config_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config", type=Path, help="cell configuration TOML (see configs/cell.toml)")


def cell_config(args: argparse.Namespace, gui: bool = False):
    """CellConfig from --config (or the defaults), with the camera seeded by --seed."""
    from app.config import load_toml
    from app.simcell.cell import CellConfig

    config = load_toml(CellConfig, args.config) if args.config else CellConfig()
    config = replace(config, camera_seed=args.seed)
    if gui:
        config = replace(config, world=replace(config.world, gui=True))
    return config


def add_job_config_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--job-config", type=Path, help="job settings TOML (see configs/job.toml); --method, --demos and "
                   "--second-look override it")


def job_config(args: argparse.Namespace):
    """JobConfig from --job-config (or the defaults), with --method, --demos and --second-look where given;
    args.method becomes the method the job runs."""
    from app.config import load_toml
    from app.jobs.settings import JobConfig

    job = load_toml(JobConfig, args.job_config) if args.job_config else JobConfig()
    predict = job.predict
    if args.method is not None:
        predict = replace(predict, method=args.method)
    if getattr(args, "demos", None) is not None:
        predict = replace(predict, demos=args.demos)
    second_look = job.second_look if args.second_look is None else args.second_look
    job = replace(job, predict=predict, second_look=second_look)
    args.method = job.method
    return job


def add_imitation_arguments(p: argparse.ArgumentParser) -> None:
    """--inits, --iterations, --prune-every, --patience, --explore-points, --{grasp,place}-contact-scale,
    --place-demo-match."""
    from app.nift.imitation_config import DEMO_MATCHES
    from app.nift.imitation_config import ImitationConfig as C

    p.add_argument("--inits", type=int, default=C.inits, help=f"parallel initialisations (paper: 10; default {C.inits})")
    p.add_argument("--iterations", type=int, default=C.iterations,
                   help="at most this many Adam steps per template; the step size decays over them (paper: 500)")
    p.add_argument("--prune-every", type=int, default=C.prune_every,
                   help="drop the worse half of the initialisations every N steps (0: the paper's, no pruning)")
    p.add_argument("--patience", type=int, default=C.patience,
                   help="stop when no initialisation improved for this many steps")
    p.add_argument("--explore-points", type=int, default=C.explore_points,
                   help="template points the loss uses while pruning (0: all)")
    p.add_argument("--grasp-contact-scale", type=float, default=C.grasp_contact_scale,
                   help="metres: weight grasp template points by exp(-d / scale), d their distance to the gripper (0: the paper's mean)")
    p.add_argument("--place-contact-scale", type=float, default=C.place_contact_scale,
                   help="metres: the same for place templates (distance to the rack or shelf; 0: the paper's mean)")
    p.add_argument("--place-demo-match", choices=DEMO_MATCHES, default=C.place_demo_match,
                   help="compare place poses with the demos' mean features (mean, the paper's) or each demo's own, "
                        "taking the nearest (nearest)")


def imitation_config(args: argparse.Namespace):
    """ImitationConfig from the options above and --seed."""
    from app.nift.imitation_config import ImitationConfig

    return ImitationConfig(inits=args.inits, iterations=args.iterations, prune_every=args.prune_every,
                           patience=args.patience, explore_points=args.explore_points,
                           grasp_contact_scale=args.grasp_contact_scale,
                           place_contact_scale=args.place_contact_scale, place_demo_match=args.place_demo_match,
                           seed=args.seed)


def add_second_look_argument(p: argparse.ArgumentParser) -> None:
    """--second-look: the job's second look at the held object (`app.jobs.second_look`)."""
    p.add_argument("--second-look", action=argparse.BooleanOptionalAction, default=None,
                   help="after the lift, show the held object to the camera and choose the place again from what it "
                        "shows (template methods; default: on for hangs, off for the shelf; docs/jobs.md)")


MAX_WORKERS = 256


def add_cluster_arguments(p: argparse.ArgumentParser, what: str, default: int = 2, why: str = "one per core") -> None:
    """--workers and --address: how wide a verb fans out on Ray (app.fanout), and where."""
    p.add_argument("--workers", type=int, default=default,
                   help=f"{what} run at once on a local Ray (default {default}: {why}; 1: in this process, in order)")
    p.add_argument("--address", metavar="HOST:PORT", default=None,
                   help="run on the Ray cluster whose head is there (default $RAY_ADDRESS; unset: a local Ray for this "
                        "command); its CPUs set the width (docs/scale.md)")


def cluster_of(args: argparse.Namespace):  # -> app.fanout.cluster.ClusterConfig
    """The verb's ClusterConfig from --workers and --address (checked: a one-line error)."""
    from app.fanout.cluster import check_reachable, cluster_config

    config = cluster_config(check_workers(args.workers), args.address)
    if config.address is not None:
        check_reachable(config.address)  # before anything is written
    return config


def check_workers(workers: int) -> int:
    """--workers as given, or a one-line error when it is not a count of processes."""
    if not 1 <= workers <= MAX_WORKERS:
        raise ValueError(f"--workers must be in [1, {MAX_WORKERS}] processes, got {workers}")
    return workers
