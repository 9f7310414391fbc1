"""`nift objects`: render a contact sheet of procedural instances (and optionally export them);
`nift objects import` brings a user's mesh into the local object library, `nift objects list` lists it."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from app.categories import SPLIT_NAMES
from app.console.options import add_cluster_arguments

NAME = "objects"
HELP = "render a contact sheet of procedural object instances; import your own meshes (objects import)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from app.categories import CATEGORIES

    actions = p.add_subparsers(dest="action", metavar="ACTION")
    imp = actions.add_parser("import", help="bring a mesh file (OBJ, STL, PLY, GLB) into the local object library")
    imp.add_argument("mesh", type=Path, help="the mesh file")
    imp.add_argument("--category", required=True, choices=CATEGORIES, help="which category it is an object of")
    imp.add_argument("--name", help="the name it is used by (default: the file's stem, lower-cased)")
    imp.add_argument("--units", choices=("m", "cm", "mm", "in"),
                     help="the file's length unit (default: inferred from the size when only one unit fits)")
    imp.add_argument("--up", default="z", choices=("z", "y", "x", "-z", "-y", "-x"),
                     help="the file's axis that points up (default z; many scanners and GLB files use y)")
    imp.add_argument("--collision-faces", type=int, default=2000,
                     help="triangles the mesh is simplified to before convex decomposition (default 2000)")
    imp.add_argument("--replace", action="store_true", help="overwrite an object of the same name")
    imp.add_argument("--json", action="store_true", help="print the object's record as JSON")
    many = actions.add_parser("import-set", help="import every mesh of a set file (e.g. shapes/real/set.toml)")
    many.add_argument("set", type=Path, help="a TOML file of [[object]] tables (app.objects.shape_set)")
    many.add_argument("--replace", action="store_true", help="import again the objects already in the library")
    many.add_argument("--json", action="store_true", help="print what each import did as JSON")
    add_cluster_arguments(many, "meshes")
    actions.add_parser("list", help="list the objects in the local object library ($NIFT_OBJECTS)")
    p.add_argument("--category", default="mug", choices=CATEGORIES, help="object category (default: mug)")
    p.add_argument("--count", type=int, default=16, help="number of instances (default: 16)")
    p.add_argument("--split", default="test", choices=SPLIT_NAMES, help="seed split to draw from")
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
    if getattr(args, "action", None) == "import":
        return import_mesh(args)
    if getattr(args, "action", None) == "import-set":
        return import_many(args)
    if getattr(args, "action", None) == "list":
        return list_objects()
    return contact(args)


def import_mesh(args: argparse.Namespace) -> int:
    """`nift objects import`: check, repair, scale, frame, decompose and store a mesh."""
    from app.objects import library

    if not 100 <= args.collision_faces <= 100_000:
        raise ValueError(f"--collision-faces must be between 100 and 100000, got {args.collision_faces}")
    name = args.name or args.mesh.stem.lower()
    library.check_name(name)
    obj, notes = library.import_object(args.mesh, args.category, name, args.units, args.up, replace=args.replace,
                                       faces=args.collision_faces)
    if args.json:
        print(json.dumps({"name": obj.name, "directory": str(obj.collision.parent), **obj.info}, indent=2))
    else:
        print(f"{obj.name} ({obj.category}) -> {obj.collision.parent}")
        for note in notes:
            print(f"  {note}")
    return 0


def import_many(args: argparse.Namespace) -> int:
    """`nift objects import-set`: import the set's meshes not in the library yet."""
    from app.console.options import cluster_of
    from app.objects.shape_set import import_set

    done = import_set(args.set, replace=args.replace, cluster=cluster_of(args))
    if args.json:
        print(json.dumps([{"name": e.name, "category": e.category, "imported": notes is not None,
                           "notes": notes or []} for e, notes in done], indent=2))
        return 0
    for e, notes in done:
        print(f"{e.name:20s} {e.category:7s} " + ("already in the library" if notes is None else "imported"))
        for note in notes or []:
            print(f"  {note}")
    return 0


def list_objects() -> int:
    """`nift objects list`."""
    from app.objects import library

    names = library.object_names()
    if not names:
        print(f"no objects in {library.library_dir()} (nift objects import MESH --category C --name N)")
    for name in names:
        obj = library.load_object(name)
        x, y, z = (100 * e for e in obj.info["extents_m"])
        print(f"{name:24s} {obj.category:7s} {x:5.1f} x {y:5.1f} x {z:5.1f} cm  from {obj.info['source']}")
    return 0


def contact(args: argparse.Namespace) -> int:
    """The contact sheet of procedural instances."""
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
