"""Bring-your-own objects: load an OBJ / STL / PLY / GLB mesh and check it is usable."""
from __future__ import annotations

from pathlib import Path

import trimesh

FORMATS = (".obj", ".stl", ".ply", ".glb", ".gltf", ".off")


def load_mesh(path: str | Path, upright: bool = False) -> trimesh.Trimesh:
    """A single watertight triangle mesh from a file, or a one-line ValueError saying what is wrong.

    Multi-part files (GLB scenes) are merged. With `upright=True` the mesh is moved so that its
    lowest point rests on z = 0 and its bounding-box centre is on the z axis (our canonical frame
    for objects whose file frame is already z-up).
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such mesh file")
    if path.suffix.lower() not in FORMATS:
        raise ValueError(f"{path}: unsupported mesh format {path.suffix!r}; use one of {', '.join(FORMATS)}")
    try:
        loaded = trimesh.load(path, force="mesh", process=True)
    except Exception as exc:  # trimesh raises many types for corrupt files
        raise ValueError(f"{path}: could not read as {path.suffix} ({exc})") from exc
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ValueError(f"{path}: holds no triangles")
    if not loaded.is_watertight:
        open_edges = len(trimesh.grouping.group_rows(loaded.edges_sorted, require_count=1))
        raise ValueError(f"{path}: mesh is not watertight ({open_edges} open edges); close its holes "
                         f"(e.g. trimesh.repair.fill_holes or a remesh) before using it")
    if loaded.volume < 0:
        loaded.invert()
    if upright:
        lo, hi = loaded.bounds
        loaded.apply_translation([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
    loaded.metadata["name"] = path.stem
    return loaded
