"""`nift bench-geometry`: ray, SCF and IBS throughput and accuracy on this machine."""
from __future__ import annotations

import argparse

from app.console.output import print_figures

NAME = "bench-geometry"
HELP = "measure Embree ray rate, SCF throughput/accuracy and IBS time on this machine"

TARGETS = {"scf_fraction_of_raw": ">= 0.8", "ibs_seconds": "<= 0.5"}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quick", action="store_true", help="fewer points (CI size); figures are noisier")
    p.add_argument("--seed", type=int, default=0, help="seed of the random query points and rotation")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")


def run(args: argparse.Namespace) -> int:
    from app.bench.geometry import run_geometry_benchmark

    figures = run_geometry_benchmark(quick=args.quick, seed=args.seed)
    print_figures(figures, args.json, TARGETS)
    return 0
