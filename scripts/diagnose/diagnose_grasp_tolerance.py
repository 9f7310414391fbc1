"""How far off the scripted teacher's bowl grasp may be and still hold under the teleported judge
(docs/additions.md, "Grasp centring"; app/predict/grasp_centering.py).

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_grasp_tolerance.py   (4 test bowls, ~30 s)
The teacher's TCP frame: y across the wall towards the bowl's axis, z the approach (down the wall).
"""
import numpy as np

from app.objects import split
from app.simcell.judges import judge_grasp
from app.simcell.spawn import spawn
from app.tasks.task import teacher_grasp
from hardware.se3 import make_pose, rotvec_to_matrix
from hardware.sim.world import SimWorld, SimWorldConfig

OFFSETS = {"as taught": make_pose(),
           "5 mm towards the axis": make_pose(np.eye(3), [0, 0.005, 0]),
           "10 mm towards the axis": make_pose(np.eye(3), [0, 0.010, 0]),
           "5 mm away from the axis": make_pose(np.eye(3), [0, -0.005, 0]),
           "10 mm deeper": make_pose(np.eye(3), [0, 0, 0.010]),
           "15 mm deeper": make_pose(np.eye(3), [0, 0, 0.015]),
           "tilted 15 deg outwards": make_pose(rotvec_to_matrix([0.26, 0, 0])),
           "tilted 15 deg inwards": make_pose(rotvec_to_matrix([-0.26, 0, 0]))}

world = SimWorld(SimWorldConfig())
world.connect()
held = {name: 0 for name in OFFSETS}
seeds = split("bowl", "test")[:4]
for seed in seeds:
    for name, offset in OFFSETS.items():
        obj = spawn(world, "bowl", seed, "upright", T_world_obj=make_pose(np.eye(3), [0.5, 0.0, 0.0]))
        held[name] += judge_grasp(world, obj, world.pose(obj.body) @ teacher_grasp(obj.mesh) @ offset).success
        world.remove(obj.body)
for name, n in held.items():
    print(f"{name:26s} held {n} of {len(seeds)}")
