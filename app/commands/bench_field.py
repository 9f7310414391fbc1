"""`nift bench-field`: data generation, training and feature throughput on this machine."""
from __future__ import annotations

import argparse

from app.console.output import print_figures

NAME = "bench-field"
HELP = "measure field data generation, training throughput and feature forward+backward time"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quick", action="store_true", help="fewer samples and repeats (CI size)")
    p.add_argument("--workers", type=int, default=2, help="data generation worker processes")
    p.add_argument("--seed", type=int, default=0, help="data seed")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")


def run(args: argparse.Namespace) -> int:
    from app.bench.field import run_field_benchmark

    print_figures(run_field_benchmark(quick=args.quick, seed=args.seed, workers=args.workers), args.json)
    return 0
