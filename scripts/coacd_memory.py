"""Resident memory of this process over CoACD decompositions of new mugs: in a child process (as
`app.objects.collision.decompose` runs it) or in this process (as it ran before).

Usage (repo root): .venv/bin/python scripts/coacd_memory.py FIRST_SEED LAST_SEED {child,inproc}
e.g. `930 938 child` (~20 s a mug). Prints the resident MB before and after each decomposition.
"""
import argparse
import gc
import os

import numpy as np
import trimesh

from app.objects import generate
from app.objects.collision import DecompositionConfig, decompose


def resident_mb() -> float:
    with open(f"/proc/{os.getpid()}/status") as status:
        return next(int(line.split()[1]) / 1024 for line in status if line.startswith("VmRSS"))


def in_this_process(mesh: trimesh.Trimesh, config: DecompositionConfig = DecompositionConfig()) -> list:
    import coacd

    coacd.set_log_level("error")
    parts = coacd.run_coacd(coacd.Mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces)), threshold=config.threshold,
                            resolution=config.resolution, preprocess_mode="off", mcts_iterations=config.mcts_iterations,
                            mcts_max_depth=config.mcts_depth, mcts_nodes=config.mcts_nodes, seed=config.seed)
    return [trimesh.Trimesh(v, f, process=False).convex_hull for v, f in parts]


parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("first", type=int)
parser.add_argument("last", type=int)
parser.add_argument("where", choices=("child", "inproc"))
args = parser.parse_args()
meshes = [generate("mug", seed).copy() for seed in range(args.first, args.last)]  # made first: not measured
run = decompose if args.where == "child" else in_this_process
gc.collect()
print(f"{args.where}: {resident_mb():.1f} MB before", flush=True)
for seed, mesh in zip(range(args.first, args.last), meshes):
    parts = run(mesh)
    del parts
    gc.collect()
    print(f"mug {seed}: {resident_mb():.1f} MB", flush=True)
