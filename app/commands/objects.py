"""`nift objects`: render a contact sheet of procedural instances (and optionally export them)."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

NAME = "objects"
HELP = "render a contact sheet of procedural object instances; optionally export meshes"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from app.categories import CATEGORIES

    p.add_argument("--category", default="mug", choices=CATEGORIES, help="object category (default: mug)")
    p.add_argument("--count", type=int, default=16, help="number of instances (default: 16)")
    p.add_argument("--split", default="test", choices=["train", "test"], help="seed split to draw from")
    p.add_argument("--seed", type=int, default=0, help="picks which instances of the split are drawn")
    p.add_argument("--out", type=Path, default=Path("objects.png"), help="contact sheet PNG path")
    p.add_argument("--export", type=Path, metavar="DIR", help="also write each instance as DIR/<name>.obj")
    p.add_argument("--json", action="store_true", help="print the instances' semantics as JSON")


def pick_seeds(category: str, split_name: str, count: int, seed: int) -> list[int]:
    """`count` distinct instance seeds of a split, drawn reproducibly with `seed`."""
    from app.objects import split

    seeds = split(category, split_name)
    if not 1 <= count <= len(seeds):
        raise ValueError(f"--count must be between 1 and {len(seeds)}, got {count}")
    return sorted(np.random.default_rng(seed).choice(seeds, size=count, replace=False).tolist())


def run(args: argparse.Namespace) -> int:
    from app.io_utils import writable_directory, writable_file
    from app.objects import generate, semantics
    from app.objects.sheet import contact_sheet

    if args.out.suffix.lower() != ".png":
        raise ValueError(f"--out {args.out}: the contact sheet is a PNG; give a .png path")
    writable_file(args.out, "--out")
    if args.export:
        writable_directory(args.export, "--export")
    seeds = pick_seeds(args.category, args.split, args.count, args.seed)
    meshes = [generate(args.category, s) for s in seeds]
    contact_sheet(meshes, [f"{args.category} {s}" for s in seeds], args.out)
    if args.export:
        from app.io_utils import atomic_path

        for mesh in meshes:
            with atomic_path(args.export / f"{mesh.metadata['name']}.obj") as tmp:
                mesh.export(tmp, file_type="obj")
    sems = [semantics(m).to_dict() for m in meshes]
    if args.json:
        print(json.dumps({"sheet": str(args.out), "instances": sems}, indent=2))
    else:
        print(f"{len(meshes)} {args.category} instances ({args.split} split) -> {args.out}")
        for sem in sems:
            print(f"  seed {sem['seed']:>6}  height {sem['height'] * 100:5.1f} cm  "
                  f"max radius {sem['max_radius'] * 100:4.1f} cm  rim at {sem['rim_height'] * 100:5.1f} cm")
    return 0
