"""Self-imitation with three optimiser settings (paper / cosine decay / decay + pruning) on a ray-cast mug demo.

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_self_imitation.py WEIGHTS THREADS
The figures in docs/ came from an early checkpoint: runs/nif/best.pt after epoch 1, one thread.
"""
import sys
import time

import numpy as np
import torch

torch.set_num_threads(int(sys.argv[2]))
sys.path.insert(0, 'tests')
from test_imitation import demo_scene, errors

from app.nift.field import load_field
from app.nift.imitate import ImitationConfig, imitate
from app.nift.template import build_template
from app.tasks.anchors import anchor_mesh

w = sys.argv[1]
cloud, T_tcp, T_rack = demo_scene()
f = load_field(w)
cfgs = {"paper": ImitationConfig(seed=1, lr_final_ratio=1.0), "decay": ImitationConfig(seed=1, lr_final_ratio=0.05),
        "decay+prune": ImitationConfig(seed=1, lr_final_ratio=0.05, prune_every=50, iterations=300, patience=30)}
for name, anchor, T in (("grasp", "gripper", T_tcp), ("place", "rack", T_rack)):
    t = build_template(anchor, anchor_mesh(anchor), [{"cloud": cloud, "T_frame_anchor": T}], weights=w)
    for cn, c in cfgs.items():
        t0 = time.time(); r = imitate(t, cloud, c, field=f)
        e = errors(r.T, T)
        print(name, cn, round(e[0]*1000,1), 'mm', round(e[1],1), 'deg', r.iterations, round(time.time()-t0,1), 's', np.round(np.sort(r.losses)[:3],3), flush=True)
