"""Resident memory of this process over CoACD decompositions of new mugs: in a child process (as
`app.objects.collision.decompose` runs it) or in this process (as it ran before).

Usage (repo root): .venv/bin/python scripts/diagnose/coacd_memory.py FIRST_SEED LAST_SEED {child,inproc}
e.g. `930 938 child` (~20 s a mug). Prints the resident MB before and after each decomposition.
"""
import argparse
import gc

from app.bench.memory import resident_mb
from app.objects import generate
from app.objects.collision import decompose, run_coacd

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("first", type=int)
parser.add_argument("last", type=int)
parser.add_argument("where", choices=("child", "inproc"))
args = parser.parse_args()
meshes = [generate("mug", seed).copy() for seed in range(args.first, args.last)]  # made first: not measured
run = decompose if args.where == "child" else run_coacd
gc.collect()
print(f"{args.where}: {resident_mb():.1f} MB before", flush=True)
for seed, mesh in zip(range(args.first, args.last), meshes):
    parts = run(mesh)
    del parts
    gc.collect()
    print(f"mug {seed}: {resident_mb():.1f} MB", flush=True)
