"""Where NIFT's hang leaves the handle's hole, along its long axis, before and after peg centring, and
the place judge's verdict on both (docs/additions.md, "Peg centring").

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_peg_centering.py [FIRST LAST]   (default 0 20; ~6 s per mug)
Targets: test mugs FIRST..LAST-1, upright at a random yaw and place, seen by the cell's Kinect
(`nift bench-imitation`'s targets; the same mugs for any FIRST); contact weighting on.
"""
import sys

import numpy as np
from rack_judge import RackJudge

from app.bench.imitation import target
from app.nift.imitate import ImitationConfig, imitate
from app.objects import fixture, semantics, split
from app.predict.peg_centering import center_on_peg, peg_frame
from app.simcell.cell import CellConfig
from app.tasks.demo_library import task_templates
from app.tasks.task import task
from hardware.se3 import invert, transform_points

first, last = (int(sys.argv[1]), int(sys.argv[2])) if len(sys.argv) > 2 else (0, 20)
t, cell, rack = task("mug"), CellConfig(), fixture("rack")
template = task_templates(t)["place"]
o, d, e1, e2 = peg_frame(rack)
judge = RackJudge(cell)
rng = np.random.default_rng(5)
counts = np.zeros(2, int)
for i, seed in enumerate(split("mug", "test")[:last]):
    mesh, T_base_obj, cloud, scale = target("mug", seed, rng, cell)  # drawn for every i: the same mugs
    if i < first:
        continue
    seen = imitate(template, cloud, ImitationConfig(seed=0)).T
    poses = [invert(T) @ T_base_obj for T in (seen, center_on_peg(seen, cloud, rack))]  # T_rack_obj
    hole = np.array(semantics(mesh).handle_center) * scale
    side = [1000 * (transform_points(T, hole[None])[0] - o) @ e2 for T in poses]
    ok = [judge.hangs(seed, scale, T_base_obj, T) for T in poses]
    counts += ok
    print(f"mug {seed}: hole {side[0]:+5.1f} -> {side[1]:+5.1f} mm along e2 from the peg; hangs {ok[0]} -> {ok[1]}", flush=True)
print(f"mugs {first}..{last - 1}: {counts[0]} hang as imitated, {counts[1]} after peg centring")
