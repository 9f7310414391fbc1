"""The demos a benchmark run imitates.

The recorded ones (`demos/<task>/`, or `--demo-dir`'s, seen by the cell's Kinect) when the run uses
all ten and the single camera. Otherwise a copy in `<out>/demos/<task>/`: the first `--demos N` of
them, and with
`--camera fused` each demo's cloud ray cast again from the four fused cameras at the demo object's
recorded pose - in the paper's simulated setting demos and test objects are both seen fused, so a
template built from single-view demo clouds would compare unlike with unlike. The copies are made
once, before the workers start, and kept (a resumed run reuses them).
"""
from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import numpy as np

from app.bench.protocol import BenchConfig, trial_cloud
from app.objects.catalog import generate
from app.objects.library import load_object
from app.simcell.cell import CellConfig
from app.tasks.demo import DEMO_GLOB, Demo, load_demo, save_demo
from app.tasks.demo_library import DEMOS_DIR
from app.tasks.task import task


def seen_by(demo: Demo, camera: str, cell: CellConfig, seed: int) -> Demo:
    """The demo with its cloud as the camera setting sees its object at the recorded pose."""
    mesh = load_object(demo.object).mesh if demo.object else generate(demo.category, demo.seed)
    mesh.apply_scale(demo.scale)
    cloud = trial_cloud(mesh, demo.T_base_obj, camera, np.random.default_rng(seed), cell)
    return dataclasses.replace(demo, cloud=cloud)


def bench_demos(config: BenchConfig, out: Path) -> Path:
    """The directory whose `<task>/` folders hold the run's demos (made on first use)."""
    source = Path(config.demo_dir) if config.demo_dir else DEMOS_DIR
    folders = sorted({task(t).demos for t in config.tasks})
    if config.demos == 10 and config.camera == "single":
        return source
    root = out / "demos"
    for name in folders:
        target = root / name
        target.mkdir(parents=True, exist_ok=True)
        for i, path in enumerate(sorted((source / name).glob(DEMO_GLOB))[: config.demos]):
            dest = target / path.name
            if dest.exists():
                continue
            if config.camera == "single":
                shutil.copy2(path, dest)
            else:
                save_demo(seen_by(load_demo(path), config.camera, config.cell, seed=i), dest)
    return root
