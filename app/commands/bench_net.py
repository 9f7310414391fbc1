"""`nift bench-net`: the networked devices' latency, streaming rate, frame delivery and job time."""
from __future__ import annotations

import argparse
from pathlib import Path

from app.console.output import print_figures

NAME = "bench-net"
HELP = "measure the device servers: state-read latency, streaming rate, depth frame delivery, job time in-process vs network"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--reads", type=int, default=2000, help="state reads timed")
    p.add_argument("--frames", type=int, default=50, help="depth frames timed")
    p.add_argument("--jobs", type=int, default=3, help="jobs run each way (in-process and over the network)")
    p.add_argument("--task", default="bowl", choices=["mug", "bowl", "bottle"], help="the jobs' task")
    p.add_argument("--method", default="nift", help="the jobs' method")
    p.add_argument("--seed", type=int, default=0, help="first job's seed")
    p.add_argument("--calibration", type=Path, default=Path("calibration.json"),
                   help="camera calibration file; if missing, the cell is calibrated first and it is written")
    p.add_argument("--quick", action="store_true", help="CI size: 200 reads, 5 frames, 1 job")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")


def run(args: argparse.Namespace) -> int:
    if args.quick:
        args.reads, args.frames, args.jobs = 200, 5, 1
    for name in ("reads", "frames"):
        if getattr(args, name) < 1:
            raise ValueError(f"--{name} must be at least 1")
    if args.jobs < 0:
        raise ValueError("--jobs must be at least 0")

    from app.bench.net import run_net_benchmark

    print_figures(run_net_benchmark(args.reads, args.frames, args.jobs, args.task, args.method, args.seed,
                                    args.calibration), args.json)
    return 0
