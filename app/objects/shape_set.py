"""A named set of mesh files to import and run together: a TOML file of `[[object]]` tables.

    [[object]]
    name = "shampoo-oval"        # the library name (nift run --object NAME)
    category = "bottle"
    file = "shampoo-oval.obj"    # relative to the set file
    units = "m"                  # optional: the file's unit (default: inferred from the size)
    up = "y"                     # optional: the file's up axis (default z)
    product = "..."              # optional: what it is modelled after
    package = "pybullet_data"    # optional: `file` is inside this installed Python package instead

The team's real-shape set is `shapes/real/set.toml` (scripts/make_shape_set.py). The meshes are
made into objects as Ray tasks (app.fanout; each file shipped to its worker) and stored here.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from app.categories import CATEGORIES
from app.fanout.cluster import ClusterConfig
from app.fanout.run import fan_out
from app.fanout.shipping import Parcel, landed, pack
from app.objects.library import (Imported, LibraryObject, check_name, check_new, library_dir, load_object, make_object,
                                 object_names, store_object)

KEYS = {"name", "category", "file", "units", "up", "product", "package"}


@dataclass(frozen=True)
class SetEntry:
    """One mesh of a set."""

    name: str
    category: str
    file: Path
    units: str | None = None
    up: str = "z"
    product: str = ""


def read_set(path: Path) -> list[SetEntry]:
    """The set's entries, or a one-line ValueError naming the file and what is wrong."""
    try:
        tables = tomllib.loads(Path(path).read_text()).get("object", [])
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not a readable object set ({exc})") from None
    if not tables:
        raise ValueError(f"{path}: no [[object]] tables")
    entries = []
    for i, t in enumerate(tables, 1):
        unknown = set(t) - KEYS
        missing = {"name", "category", "file"} - set(t)
        if unknown or missing:
            raise ValueError(f"{path}: object {i}: " + "; ".join(
                [f"unknown key(s) {', '.join(sorted(unknown))}"] * bool(unknown)
                + [f"missing {', '.join(sorted(missing))}"] * bool(missing)))
        if t["category"] not in CATEGORIES:
            raise ValueError(f"{path}: object {t['name']!r}: unknown category {t['category']!r}")
        check_name(t["name"])
        folder = _package_dir(t["package"], path) if "package" in t else Path(path).parent
        entries.append(SetEntry(t["name"], t["category"], folder / t["file"], t.get("units"),
                                t.get("up", "z"), t.get("product", "")))
    names = [e.name for e in entries]
    if len(set(names)) != len(names):
        raise ValueError(f"{path}: a name is used twice ({', '.join(sorted({n for n in names if names.count(n) > 1}))})")
    return entries


def _package_dir(package: str, path: Path) -> Path:
    """The folder of an installed Python package, or a one-line error naming the set file."""
    import importlib.util

    spec = importlib.util.find_spec(package) if package.isidentifier() else None
    if spec is None or not spec.submodule_search_locations:
        raise ValueError(f"{path}: package {package!r} is not installed")
    return Path(list(spec.submodule_search_locations)[0])


def _nothing(payload: None) -> None:
    return None


def _make(_, job: tuple[SetEntry, Parcel]) -> Imported:
    """A worker's task: one entry's mesh, from its shipped file, made into an object."""
    e, parcel = job
    return make_object(landed(parcel), e.category, e.units, e.up)


def import_set(path: Path, directory: Path | None = None, replace: bool = False,
               cluster: ClusterConfig = ClusterConfig(1)) -> list[tuple[SetEntry, list[str] | None]]:
    """Import every entry not in the library yet (all with `replace`), the meshes made on `cluster`;
    (entry, the import's notes, None when it was there already) each, in the set's order. A file that
    cannot be imported is named in a one-line error after the others are stored."""
    root = directory or library_dir()
    have = set(object_names(root))
    entries = read_set(path)
    todo = [e for e in entries if replace or e.name not in have]
    for e in todo:
        check_new(e.category, e.name, root, replace)
    notes: dict[str, list[str]] = {}
    failed = []
    for outcome in fan_out(_make, [(e, pack(e.file)) for e in todo], _nothing, None, cluster):
        e = todo[outcome.index]
        if outcome.failed:
            failed.append(f"{e.file.name}: {outcome.error}")
            continue
        outcome.value.info["source"] = str(e.file.resolve())  # where the user's file is, not the worker's copy
        store_object(outcome.value, e.name, root, replace)
        notes[e.name] = outcome.value.notes
    if failed:
        raise ValueError(f"{path}: {len(failed)} of {len(todo)} meshes could not be imported ({'; '.join(failed)})")
    return [(e, notes.get(e.name)) for e in entries]


def set_objects(path: Path, directory: Path | None = None) -> dict[str, list[LibraryObject]]:
    """The set's objects by category, imported first where missing."""
    out: dict[str, list[LibraryObject]] = {}
    for e, _ in import_set(path, directory):
        out.setdefault(e.category, []).append(load_object(e.name, directory, e.category))
    return out


def named_objects(spec: str, directory: Path | None = None) -> dict[str, list[LibraryObject]]:
    """Objects by category from a set file's path (imported first where missing) or a comma list of
    library names; a one-line error for an unknown name or an unreadable set."""
    if spec.endswith(".toml") or Path(spec).is_file():
        return set_objects(Path(spec), directory)
    out: dict[str, list[LibraryObject]] = {}
    for name in (n.strip() for n in spec.split(",") if n.strip()):
        obj = load_object(name, directory)
        out.setdefault(obj.category, []).append(obj)
    if not out:
        raise ValueError(f"--objects {spec!r}: name a set file or library objects")
    return out
