"""How much of a mug's handle each bench trial's cloud shows, and the place success of a method
against it (docs/limits.md): from one Kinect the handle is sometimes entirely hidden
behind the mug, and then no method sees where the peg has to go.

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_handle_visibility.py RUN [--method ibs-nif]
e.g. `out/bench-t100` (about 1 minute for 200 trials). RUN is a `nift bench` directory with mug
trials; the clouds are rebuilt from its seed and camera setting, as the bench drew them.
"""
import argparse
import json
from pathlib import Path

import numpy as np

from app.bench.protocol import BenchConfig, Trial
from app.bench.trial import TeleportedBench
from hardware.se3 import invert, transform_points

BINS = ((0, 1), (1, 30), (30, 10**6))  # cloud points on the handle
WALL_MARGIN = 0.004  # metres beyond the body's outer radius where the handle starts


def handle_points(mesh, T_base_obj: np.ndarray, cloud: np.ndarray) -> int:
    """Cloud points (base frame) on the handle: on its +x side, further from the axis than the body."""
    v = np.asarray(mesh.vertices)  # (V, 3), object frame; the handle is on +x (app.objects.handle)
    body = np.percentile(np.hypot(v[:, 0], v[:, 1])[v[:, 0] < 0], 99) + WALL_MARGIN
    c = transform_points(invert(T_base_obj), cloud)  # (N, 3), object frame
    return int(((np.hypot(c[:, 0], c[:, 1]) > body) & (c[:, 0] > 0)).sum())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("--method", default="ibs-nif")
    args = parser.parse_args()
    if not (args.run / "run.json").is_file() or not (args.run / "results.jsonl").is_file():
        raise SystemExit(f"{args.run} is not a nift bench directory (no run.json and results.jsonl)")
    settings = json.loads((args.run / "run.json").read_text())
    config = BenchConfig(camera=settings["camera"], seed=settings["seed"])
    rows = [json.loads(line) for line in (args.run / "results.jsonl").read_text().splitlines()]
    placed = {(r["pose"], r["index"]): r["place"] for r in rows if r["task"] == "mug" and r["method"] == args.method}
    if not placed:
        raise SystemExit(f"{args.run} has no mug trials of {args.method}")
    bench = TeleportedBench(config.cell)
    seen: dict[str, list[tuple[int, bool]]] = {}
    for (pose, i), ok in sorted(placed.items()):
        obj, T_base_obj, cloud = bench.observe(Trial("mug", pose, i), config.camera, config.seed)
        seen.setdefault(pose, []).append((handle_points(obj.mesh, T_base_obj, cloud), ok))
    for pose, pairs in seen.items():
        n, ok = np.array(pairs).T
        for lo, hi in BINS:
            m = (n >= lo) & (n < hi)
            rate = f"{ok[m].mean():.2f}" if m.any() else "-"
            print(f"{pose:>9} handle points [{lo}, {hi if hi < 10**6 else 'inf'}): {m.sum():3d} trials, {args.method} place {rate}")


if __name__ == "__main__":
    main()
