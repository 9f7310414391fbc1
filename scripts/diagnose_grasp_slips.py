"""Why NIFT's grasps slip: for bench trials, the 6 lowest-loss final grasps of the imitation (centred,
as the bench judges them), the grasp judge's verdict on each and how much of the cloud lies between
the fingers (README, "Where NIFT fails").

Usage (repo root): .venv/bin/python scripts/diagnose_grasp_slips.py TASK POSE FIRST LAST
e.g. `bottle arbitrary 0 25` (~50 s per trial: six judged grasps). The trials are `nift bench`'s
(seed 0): the same objects, poses and clouds. One line per trial, best first: O holds, s slips,
. closes on nothing; n = cloud points between the fingers, d = their depth along the fingers (mm).
"""
import sys

import numpy as np

from app.bench.protocol import BenchConfig, Trial, trial_cloud
from app.bench.trial import TeleportedBench
from app.cell import CellConfig
from app.feasibility import GRIP_POINTS, grips_something
from app.grasp_centering import center_grasp, swept_points
from app.judges import judge_grasp
from app.nift.imitate import imitate
from app.recorder import task_templates
from app.sim_jobs import spawn_test_object
from app.tasks import task

if len(sys.argv) != 5:
    sys.exit(__doc__)
name, pose, first, last = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
config, bench = BenchConfig(), TeleportedBench(CellConfig())
t = task(name)
template = task_templates(t)["grasp"]
best_holds = some_holds = nothing_feasible = 0
for i in range(first, last):
    rng = np.random.default_rng(Trial(name, pose, i).seed(config.seed))  # as TeleportedBench.run draws it
    obj = spawn_test_object(bench.world, t, pose, rng)
    T_base_obj = bench.world.pose(obj.body)
    bench.world.remove(obj.body)
    cloud = trial_cloud(obj.mesh, T_base_obj, config.camera, rng, bench.cell)
    found = imitate(template, cloud, config.imitation(i), None, grips_something(cloud))
    marks, held = [], []
    for k in ([found.best] + [k for k in np.argsort(found.losses) if k != found.best])[:6]:
        T = center_grasp(found.poses[k], cloud)
        between = swept_points(T, cloud)
        verdict = bench.judge_copy(obj, T_base_obj, pose, lambda o: judge_grasp(bench.world, o, T))
        mark = "O" if verdict.success else ("s" if "slipped" in verdict.reason else ".")
        depth = 1000 * np.ptp(between[:, 2]) if len(between) else 0.0
        marks.append(f"{mark} loss {found.losses[k]:.0f} n {len(between)} d {depth:.0f}")
        held.append(verdict.success)
    best_holds += held[0]
    some_holds += any(held)
    nothing_feasible += not found.feasible.any()
    extent = 1000 * np.ptp(cloud, axis=0)
    print(f"{name} {pose} {i} (cloud extent {extent[0]:.0f} x {extent[1]:.0f} x {extent[2]:.0f} mm): " + " | ".join(marks), flush=True)
print(f"trials {first}..{last - 1}: the chosen grasp holds in {best_holds}, one of the 6 best in {some_holds}; "
      f"no initialisation had {GRIP_POINTS} points between the fingers in {nothing_feasible}")
