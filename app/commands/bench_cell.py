"""`nift bench-cell`: real-time factor, Kinect frame time and perception time on this machine."""
from __future__ import annotations

import argparse

from app.console.output import print_figures

NAME = "bench-cell"
HELP = "measure the sim cell: real-time factor, camera frame and perception time, calibration error"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quick", action="store_true", help="fewer repeats (CI size)")
    p.add_argument("--seed", type=int, default=0, help="camera noise and object pose seed")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")


def run(args: argparse.Namespace) -> int:
    from app.bench.cell_speed import run_cell_benchmark

    print_figures(run_cell_benchmark(quick=args.quick, seed=args.seed), args.json)
    return 0
