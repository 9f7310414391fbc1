"""Why NIFT's grasps slip: for bench trials, the 6 lowest-loss final grasps of the imitation (centred,
as the bench judges them), the grasp judge's verdict on each and how much of the cloud lies between
the fingers (docs/additions.md, "Where NIFT fails").

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_grasp_slips.py TASK POSE TRIAL... [--camera fused]
e.g. `bottle arbitrary 0-25` or `mug upright 5 18 19 --camera fused` (~50 s per trial: six judged
grasps). The trials are `nift bench`'s (seed 0): the same objects, poses, clouds, demos and fields.
One line per trial, best first: O holds, s slips, . closes on nothing; n = cloud points between the
fingers, d = their depth along the fingers (mm), tilt = the approach axis from vertical (degrees).
"""
import argparse
import tempfile
from pathlib import Path

import numpy as np

from app.bench.demos import bench_demos
from app.bench.protocol import BenchConfig, Trial, parse_indices
from app.bench.trial import TeleportedBench
from app.nift.field import load_field
from app.nift.imitate import imitate
from app.nift.template import FEATURES, field_override
from app.predict.feasibility import grips_something
from app.predict.grasp_centering import center_grasp, swept_points
from app.simcell.judges import judge_grasp
from app.tasks.demo_library import task_templates
from app.tasks.task import task

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("task")
parser.add_argument("pose")
parser.add_argument("trials", nargs="+")
parser.add_argument("--camera", default="single")
parser.add_argument("--demos-out", default=None, help="where the bench keeps its fused demos (default: a temp dir)")
args = parser.parse_args()
config = BenchConfig(tasks=(args.task,), camera=args.camera)
bench = TeleportedBench(config.cell)
t = task(args.task)
root = bench_demos(config, Path(args.demos_out or tempfile.mkdtemp()))
template = task_templates(t, root / t.demos, "ibs", "nif", nif=config.fields)["grasp"]
field = load_field(field_override("nif", config.fields) or FEATURES["nif"])
best_holds = some_holds = 0
picked = parse_indices(args.trials)
for i in picked:
    obj, T_base_obj, cloud = bench.observe(Trial(t.name, args.pose, i), config.camera, config.seed)
    found = imitate(template, cloud, config.imitation(i), field, grips_something(cloud))
    marks, held = [], []
    for k in ([found.best] + [k for k in np.argsort(found.losses) if k != found.best])[:6]:
        T = center_grasp(found.poses[k], cloud)
        between = swept_points(T, cloud)
        verdict = bench.judge_copy(obj, T_base_obj, args.pose, lambda o: judge_grasp(bench.world, o, T))
        mark = "O" if verdict.success else ("s" if "slipped" in verdict.reason else ".")
        depth = 1000 * np.ptp(between[:, 2]) if len(between) else 0.0
        tilt = np.degrees(np.arccos(np.clip(-T[2, 2], -1, 1)))
        feas = "" if found.feasible[k] else "!"
        marks.append(f"{mark}{feas} loss {found.losses[k]:.0f} n {len(between)} d {depth:.0f} tilt {tilt:.0f}")
        held.append(verdict.success)
    best_holds += held[0]
    some_holds += any(held)
    print(f"{t.name} {args.pose} {i}: " + " | ".join(marks), flush=True)
print(f"{len(picked)} trials: the chosen grasp holds in {best_holds}, one of the 6 best in {some_holds}")
