"""The local object library: a user's own objects, imported once, used like procedural ones by name.

    $NIFT_OBJECTS (default ~/.local/share/nift-cell/objects)/
        NAME/object.json      name, category, source file, units, what the import did
        NAME/mesh.obj         the object in the canonical frame, metres, watertight
        NAME/collision.obj    its convex decomposition (CoACD on the simplified mesh)

An object's folder is built beside the library and renamed into it, so a folder that exists is whole.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from app.categories import CATEGORIES
from app.objects.collision import DecompositionConfig, decompose, read_parts_obj, write_parts_obj
from app.objects.loading import PreparedMesh, prepare_mesh, read_mesh

FORMAT = "nift-object/1"
NAME_PATTERN = re.compile(r"[a-z0-9][a-z0-9_-]{0,63}")
SIMPLIFY_TOLERANCES = (0.0002, 0.0004, 0.0008, 0.0016, 0.0032)  # m
COLLISION_FACES = 2000  # triangles CoACD decomposes at most: a 12k-face mug scan took 51 s with 4,000, 14 s with 2,000


@dataclass(frozen=True)
class LibraryObject:
    """An imported object: its name and category, its mesh (canonical frame, metres) and collision parts."""

    name: str
    category: str
    mesh: trimesh.Trimesh
    collision: Path  # OBJ of convex parts, one `o` block each (PyBullet's compound mesh)
    info: dict


def library_dir() -> Path:
    """$NIFT_OBJECTS, or ~/.local/share/nift-cell/objects."""
    return Path(os.environ.get("NIFT_OBJECTS") or Path.home() / ".local" / "share" / "nift-cell" / "objects")


def check_name(name: str) -> str:
    """The name if it can name an object (lower-case letters, digits, - and _; not a category)."""
    if not NAME_PATTERN.fullmatch(name):  # fullmatch: "$" alone lets a trailing newline through
        raise ValueError(f"object name {name!r}: use 1-64 lower-case letters, digits, '-' or '_', "
                         f"starting with a letter or digit")
    if name in CATEGORIES:
        raise ValueError(f"object name {name!r} is a category's name; choose another")
    return name


def object_names(directory: Path | None = None) -> list[str]:
    """The names of the whole objects in the library, sorted."""
    root = directory or library_dir()
    return sorted(p.parent.name for p in root.glob("*/object.json")) if root.is_dir() else []


def object_info(name: str, directory: Path | None = None, category: str | None = None) -> dict:
    """An imported object's record (object.json: its category, source, what the import did), of
    `category` if given; a one-line error for an unknown name, a foreign file or another category."""
    root = directory or library_dir()
    folder = root / name
    if not (folder / "object.json").is_file():
        known = object_names(root)
        raise ValueError(f"unknown object {name!r}; the library {root} holds "
                         f"{', '.join(known) if known else 'none'} (import one with nift objects import)")
    try:
        info = json.loads((folder / "object.json").read_text())
        if info.get("format") != FORMAT or info.get("category") not in CATEGORIES:
            raise ValueError(f"format {info.get('format')!r}, category {info.get('category')!r}")
    except (ValueError, OSError, AttributeError) as exc:
        raise ValueError(f"{folder}: not a readable library object ({exc})") from None
    if category is not None and info["category"] != category:
        raise ValueError(f"object {name!r} is a {info['category']}, not a {category}")
    return info


def load_object(name: str, directory: Path | None = None, category: str | None = None) -> LibraryObject:
    """An imported object by name (of `category` if given), or a one-line error (`object_info`)."""
    root = directory or library_dir()
    info = object_info(name, root, category)
    try:
        mesh = trimesh.load(root / name / "mesh.obj", force="mesh", process=True)
    except (ValueError, OSError) as exc:
        raise ValueError(f"{root / name}: not a readable library object ({exc})") from None
    mesh.metadata.update(name=name, imported=True, category=info["category"])
    return LibraryObject(name, info["category"], mesh, root / name / "collision.obj", info)


def simplified(mesh: trimesh.Trimesh, faces: int = COLLISION_FACES) -> trimesh.Trimesh:
    """The mesh with at most about `faces` triangles: manifold3d's simplification at a tolerance doubled
    from 0.2 mm until it is small enough (at most 3.2 mm). manifold3d keeps the result a valid solid;
    Open3D's quadric decimation could fold a union's thin caps into self-intersections on which CoACD
    ran for over 14 minutes (docs/objects.md)."""
    if len(mesh.faces) <= faces:
        return mesh
    from app.objects.mesh_repair import to_manifold

    solid = to_manifold(mesh)
    out = mesh
    for tolerance in SIMPLIFY_TOLERANCES:
        small = solid.simplify(tolerance).to_mesh()
        out = trimesh.Trimesh(np.asarray(small.vert_properties, float)[:, :3], np.asarray(small.tri_verts),
                              process=False)
        if len(out.faces) <= faces:
            break
    return out if out.is_watertight and out.volume > 0 else mesh


@dataclass
class Imported:
    """A mesh file made into an object, not stored yet: the repaired mesh, its convex parts, its record."""

    info: dict
    mesh: trimesh.Trimesh
    parts: list[trimesh.Trimesh]
    notes: list[str]


def check_new(category: str, name: str, root: Path, replace: bool) -> None:
    """A one-line error for an unknown category, a bad name, or a name taken (without `replace`)."""
    if category not in CATEGORIES:
        raise ValueError(f"unknown object category {category!r}; choose one of {', '.join(CATEGORIES)}")
    check_name(name)
    if (root / name).exists() and not replace:
        raise ValueError(f"an object named {name!r} is already in {root}; give --replace to overwrite it")


def make_object(path: Path, category: str, units: str | None = None, up: str = "z", faces: int = COLLISION_FACES,
                config: DecompositionConfig = DecompositionConfig()) -> Imported:
    """Read, repair, scale and frame a mesh file and decompose it for collisions (writes nothing)."""
    prepared = prepare_mesh(read_mesh(path), units, up, path.name)
    notes = list(prepared.notes)
    start = time.perf_counter()
    source = simplified(prepared.mesh, faces)
    parts = decompose(source, config)
    notes.append(f"collision model: {len(parts)} convex parts from {len(source.faces)} faces "
                 f"in {time.perf_counter() - start:.1f} s (CoACD)")
    return Imported(_info(path, category, prepared, notes), prepared.mesh, parts, notes)


def store_object(imported: Imported, name: str, root: Path, replace: bool = False) -> LibraryObject:
    """Write a made object into the library under `name` (atomically: a whole folder or nothing)."""
    _store(root, name, imported.info, imported.mesh, imported.parts, replace)
    return load_object(name, root)


def import_object(path: str | Path, category: str, name: str, units: str | None = None, up: str = "z",
                  directory: Path | None = None, replace: bool = False, faces: int = COLLISION_FACES,
                  config: DecompositionConfig = DecompositionConfig()) -> tuple[LibraryObject, list[str]]:
    """Read, repair, scale and frame a mesh file, decompose it for collisions and store it by name;
    (the object, what was done). Nothing is written unless every step succeeds."""
    root = directory or library_dir()
    check_new(category, name, root, replace)
    imported = make_object(Path(path), category, units, up, faces, config)
    return store_object(imported, name, root, replace), imported.notes


def _info(path: Path, category: str, prepared: PreparedMesh, notes: list[str]) -> dict:
    mesh = prepared.mesh
    return {"format": FORMAT, "category": category, "source": str(path.resolve()), "units": prepared.units,
            "metres_per_unit": prepared.scale, "extents_m": np.round(mesh.extents, 5).tolist(),
            "faces": len(mesh.faces), "volume_m3": round(float(mesh.volume), 9), "import": notes}


def _store(root: Path, name: str, info: dict, mesh: trimesh.Trimesh, parts: list[trimesh.Trimesh],
           replace: bool) -> None:
    """Write the object's folder beside the library, then rename it in (an old one goes only then)."""
    root.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{name}.", dir=root))
    try:
        mesh.export(staging / "mesh.obj", file_type="obj")
        write_parts_obj(parts, staging / "collision.obj")
        (staging / "object.json").write_text(json.dumps({"name": name, **info}, indent=2) + "\n")
        final = root / name
        if final.exists() and replace:
            old = root / f".{name}.old"
            shutil.rmtree(old, ignore_errors=True)
            final.rename(old)
            staging.rename(final)
            shutil.rmtree(old, ignore_errors=True)
        else:
            try:
                staging.rename(final)
            except OSError:  # another process imported the same name meanwhile: theirs stands, whole
                if not (final / "object.json").is_file():
                    raise
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def collision_parts(obj: LibraryObject) -> list[trimesh.Trimesh]:
    """The stored convex parts."""
    return read_parts_obj(obj.collision)
