"""Where NIFT hangs unseen mugs: the place judge's verdict and how far the handle's hole ends up from
the peg, for a contact weighting scale (docs/additions.md, "Contact weighting").

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_mug_place.py [SCALE_M [N]]   (default 0.01 20; ~5 s per mug)
SCALE_M = 0 is the paper's plain mean over the template points. Targets: the first N test mugs,
upright at a random yaw and place, seen by the cell's Kinect (`nift bench-imitation`'s targets).
"""
import sys

import numpy as np
from rack_judge import RackJudge

from app.bench.imitation import target
from app.nift.imitate import ImitationConfig, imitate
from app.objects import fixture, semantics, split
from app.simcell.cell import CellConfig
from app.tasks.demo_library import task_templates
from app.tasks.task import task
from hardware.se3 import invert

scale_m = float(sys.argv[1]) if len(sys.argv) > 1 else 0.01
n = int(sys.argv[2]) if len(sys.argv) > 2 else 20
t, cell = task("mug"), CellConfig()
template = task_templates(t)["place"]
peg = fixture("rack").landmarks
origin, direction = np.array(peg["peg_origin"]), np.array(peg["peg_direction"])
rack = RackJudge(cell)
rng = np.random.default_rng(5)
held = 0
for seed in split("mug", "test")[:n]:
    mesh, T_base_obj, cloud, scale = target("mug", seed, rng, cell)
    found = imitate(template, cloud, ImitationConfig(seed=0, place_contact_scale=scale_m))
    T_rack_obj = invert(found.T) @ T_base_obj
    hole = T_rack_obj[:3, :3] @ (np.array(semantics(mesh).handle_center) * scale) + T_rack_obj[:3, 3]
    v = hole - origin
    off_peg = np.linalg.norm(v - (v @ direction) * direction)  # distance of the hole's centre from the peg's axis
    verdict = rack.verdict(seed, scale, T_base_obj, T_rack_obj)
    held += verdict.success
    print(f"mug {seed}: handle hole {1000 * off_peg:5.1f} mm off the peg; {verdict.reason}", flush=True)
print(f"contact scale {scale_m} m: {held} of {n} hang")
