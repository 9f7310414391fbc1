"""Template loss at the found pose vs at the scripted teacher's pose on unseen test objects (shipped NIF and NITs).

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_template_loss.py [TASK ...]   (default: mug bottle)
If the found pose scores lower than the teacher's, the optimiser is not what fails: the objective is.
"""
import sys

import numpy as np
import torch

from app.bench.imitation import target
from app.nift.field import load_field
from app.nift.imitate import ImitationConfig, imitate
from app.objects import split
from app.simcell.cell import CellConfig
from app.tasks.demo_library import task_templates
from app.tasks.task import task, teacher_grasp, teacher_place
from hardware.se3 import invert

f = load_field("nif"); cell = CellConfig()
def loss_at(tpl, cloud, T):
    with torch.no_grad():
        z = f.encode(cloud); x = torch.as_tensor(tpl.points @ T[:3,:3].T + T[:3,3], dtype=torch.float32)[None]
        return float((f.features(z, x)[0] - torch.as_tensor(tpl.features)).abs().sum(-1).mean())
for name in sys.argv[1:] or ["mug", "bottle"]:
    t = task(name); tpl = task_templates(t)
    rng = np.random.default_rng(3)
    for s in split(t.category, "test")[:3]:
        mesh, T_obj, cloud, scale = target(t.category, s, rng, cell)
        Tg = T_obj @ teacher_grasp(mesh)
        Tp = T_obj @ invert(teacher_place(t, mesh, scale))  # fixture pose seen from the object
        rg = imitate(tpl["grasp"], cloud, ImitationConfig(iterations=300))
        rp = imitate(tpl["place"], cloud, ImitationConfig(iterations=300))
        print(name, s, "grasp loss teacher %.3f found %.3f | place loss teacher %.3f found %.3f" % (
            loss_at(tpl["grasp"], cloud, Tg), rg.losses.min(), loss_at(tpl["place"], cloud, Tp), rp.losses.min()), flush=True)
