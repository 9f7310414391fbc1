"""Why NIFT's 10-demo bowl grasp template fails upright (docs/additions.md, "Fewer demos").

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_bowl_grasp.py [offsets|single|cross]
  offsets  predicted vs teacher grasp on 6 test bowls, in the bowl frame (radius r, height z)
  single   a template from each single demo: bowl upright success on 6 bench trials
  cross    each single-demo template imitated on the other 9 demos' clouds: grasp error
No argument runs all three (about 6 minutes on 2 cores).
"""
import pathlib
import shutil
import sys
import tempfile

import numpy as np

from app.bench import demos as bench_demos
from app.bench import runner
from app.bench.imitation import grasp_error, target
from app.bench.protocol import BenchConfig
from app.bench.report import summarise
from app.nift.imitate import ImitationConfig, imitate
from app.nift.template import build_template
from app.objects import split
from app.predict.config import PredictConfig
from app.predict.predict import predict
from app.tasks.anchors import anchor_mesh
from app.tasks.demo_library import DEMOS_DIR, task_demos
from app.tasks.task import task, teacher_grasp
from hardware.se3 import invert


def offsets() -> None:
    t, rng = task("bowl"), np.random.default_rng(3)
    for seed in split("bowl", "test")[:6]:
        mesh, T_obj, cloud, _ = target("bowl", seed, rng)
        a = teacher_grasp(mesh)  # object frame
        b = invert(T_obj) @ predict(t, cloud, PredictConfig(method="ibs-nif", imitation=ImitationConfig(), carried_grasps=False)).T_base_tcp
        print(seed, "teacher r %.3f z %.3f | predicted r %.3f z %.3f" % (
            np.hypot(*a[:2, 3]), a[2, 3], np.hypot(*b[:2, 3]), b[2, 3]), flush=True)


def single() -> None:
    config = BenchConfig(tasks=("bowl",), poses=("upright",), methods=("ibs-nif",), trials=6)
    for k in range(10):
        root = pathlib.Path(tempfile.mkdtemp())
        (root / "bowl").mkdir()
        shutil.copy2(DEMOS_DIR / "bowl" / f"demo-{k:02d}.npz", root / "bowl")
        bench_demos.DEMOS_DIR = root  # the bench reads its demos from here (one process: workers=1)
        rows = runner.run(config, pathlib.Path(tempfile.mkdtemp()), workers=1)
        print(k, summarise(rows, ["bowl"], ["upright"], ["ibs-nif"])["upright"]["ibs-nif"]["bowl"], flush=True)


def cross() -> None:
    demos = task_demos(DEMOS_DIR / "bowl")
    for k, d_k in enumerate(demos):
        template = build_template("gripper", anchor_mesh("gripper"), [{"cloud": d_k.cloud, "T_frame_anchor": d_k.grasp_anchor()}])
        errors = np.array([grasp_error("bowl", d.T_base_obj, imitate(template, d.cloud, ImitationConfig(seed=j)).T, d.T_base_tcp)
                           for j, d in enumerate(demos) if j != k])
        print(k, "median %.1f mm %.1f deg | within 1 cm: %d/9" % (
            1000 * np.median(errors[:, 0]), np.median(errors[:, 1]), int(np.sum(errors[:, 0] < 0.01))), flush=True)


PARTS = {"offsets": offsets, "single": single, "cross": cross}
for name in sys.argv[1:] or PARTS:
    print("==", name)
    PARTS[name]()
