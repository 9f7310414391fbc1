"""`nift bench-geometry`: ray, SCF and IBS throughput and accuracy on this machine."""
from __future__ import annotations

import argparse
import json

NAME = "bench-geometry"
HELP = "measure Embree ray rate, SCF throughput/accuracy and IBS time on this machine"

TARGETS = {"scf_fraction_of_raw": 0.8, "ibs_seconds": 0.5}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quick", action="store_true", help="fewer points (CI size); figures are noisier")
    p.add_argument("--seed", type=int, default=0, help="seed of the random query points and rotation")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")


def run(args: argparse.Namespace) -> int:
    from app.bench.geometry import run_geometry_benchmark

    figures = run_geometry_benchmark(quick=args.quick, seed=args.seed)
    if args.json:
        print(json.dumps(figures, indent=2))
        return 0
    for key, value in figures.items():
        shown = f"{value:.4g}" if isinstance(value, float) else (
            "[" + ", ".join(f"{v:.3f}" for v in value) + "]" if isinstance(value, list) else str(value))
        target = ""
        if key == "scf_fraction_of_raw":
            target = f"   (target >= {TARGETS[key]})"
        elif key == "ibs_seconds":
            target = f"   (target <= {TARGETS[key]})"
        print(f"{key:<30} {shown}{target}")
    return 0
