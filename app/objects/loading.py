"""Bring-your-own objects: read a scanned or modelled mesh, repair it, put it in the canonical frame.

A scan arrives with texture seams (the same point stored once per UV island, so the surface looks
open along every seam), small holes, arbitrary units and its own "up". `prepare_mesh` merges the
seam vertices (trimesh), makes one solid of what is left (`app.objects.mesh_repair`: holes filled,
open ends capped, slivers and islands dropped, overlapping parts united), scales to metres (from `units`, or the size when that is unambiguous), turns
the file's up axis to +z and puts the object on z = 0 with the centre of its footprint (the
lowest slice's convex hull, so a mug's handle does not pull its axis off z) on the z axis.
Every step that changed something is reported in `notes`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from app.objects.mesh_repair import NotASolid, solidify

FORMATS = (".obj", ".stl", ".ply", ".glb", ".gltf", ".off")
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
UP_AXES = ("z", "y", "x", "-z", "-y", "-x")
SIZE_RANGE = (0.02, 0.6)  # m: the largest extent a graspable object can have in this cell
FOOTPRINT = 0.005  # m (after scaling): the slice above the lowest point whose hull is the footprint


@dataclass(frozen=True)
class PreparedMesh:
    """A mesh in the canonical frame, in metres, watertight, and what was done to get there."""

    mesh: trimesh.Trimesh
    notes: list[str] = field(default_factory=list)
    scale: float = 1.0  # metres per file unit
    units: str = "m"


MAX_FILE_BYTES = 512 * 1024 * 1024  # a larger file is refused before it is read
MAX_FACES = 2_000_000  # a 5-million-face scan took 144 s and 3.4 GB to import; simplify it first


def read_mesh(path: str | Path) -> trimesh.Trimesh:
    """The file's triangles as one mesh, vertices as stored (no merging); a one-line error if it is none
    or it is larger than MAX_FILE_BYTES or MAX_FACES."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such mesh file")
    if path.suffix.lower() not in FORMATS:
        raise ValueError(f"{path}: unsupported mesh format {path.suffix!r}; use one of {', '.join(FORMATS)}")
    if path.stat().st_size > MAX_FILE_BYTES:
        raise ValueError(f"{path}: {path.stat().st_size / 2**20:.0f} MB is over the {MAX_FILE_BYTES // 2**20} MB "
                         "limit for a mesh file; simplify it first")
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many types for corrupt files
        raise ValueError(f"{path}: could not read as {path.suffix} ({type(exc).__name__})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ValueError(f"{path}: holds no triangles")
    if len(loaded.faces) > MAX_FACES:
        raise ValueError(f"{path}: {len(loaded.faces):,} triangles is over the {MAX_FACES:,} limit; "
                         "simplify the mesh first (e.g. quadric decimation in Open3D or MeshLab)")
    if not np.isfinite(loaded.vertices).all():
        raise ValueError(f"{path}: has non-finite vertex coordinates")
    return loaded


def open_edges(mesh: trimesh.Trimesh) -> int:
    """Edges used by one face only (0 for a closed surface)."""
    return len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))


def repair(mesh: trimesh.Trimesh, name: str = "mesh") -> tuple[trimesh.Trimesh, list[str]]:
    """A watertight, outward-facing solid and the steps taken (`app.objects.mesh_repair.solidify` for
    several pieces, open ends, overlaps and fans); a one-line NotASolid when nothing encloses a volume."""
    notes: list[str] = []
    out = trimesh.Trimesh(np.asarray(mesh.vertices, float), np.asarray(mesh.faces), process=False)
    before, open_before = len(out.vertices), open_edges(out)
    out.merge_vertices(merge_tex=True, merge_norm=True)  # texture seams store one point several times
    if not _one_closed_body(out):  # a closed body's slivers are part of its surface: dropping them opens it
        out.update_faces(out.nondegenerate_faces())
        out.update_faces(out.unique_faces())
    out.remove_unreferenced_vertices()
    if len(out.vertices) < before:
        notes.append(f"merged {before - len(out.vertices)} duplicated vertices (texture seams); "
                     f"open edges {open_before} -> {open_edges(out)}")
    if not len(out.faces):
        raise NotASolid(f"{name}: every triangle is degenerate; it cannot be a solid object")
    if _one_closed_body(out):
        consistent = out.is_winding_consistent
        trimesh.repair.fix_normals(out)
        if out.volume > 0:
            if not consistent:
                notes.append("re-wound the faces that pointed inwards, so every normal faces out (trimesh)")
            return out, notes
    if not out.is_winding_consistent or out.body_count > 1 or not out.is_watertight:
        out, more = solidify(out, name)
        notes += more
    trimesh.repair.fix_normals(out)
    if out.volume <= 0:
        raise NotASolid(f"{name}: the repaired surface encloses no volume; it cannot be a solid object")
    return out, notes


def _one_closed_body(mesh: trimesh.Trimesh) -> bool:
    return bool(len(mesh.faces)) and mesh.is_watertight and shared_edges(mesh) == 0 and mesh.body_count == 1


def shared_edges(mesh: trimesh.Trimesh) -> int:
    """Edges used by more than two faces (non-manifold)."""
    _, counts = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
    return int((counts > 2).sum())


def metres_per_unit(extent: float, units: str | None, name: str = "mesh") -> tuple[float, str]:
    """(scale, units): the given units' scale, or the only units under which the largest extent is an
    object's size (SIZE_RANGE); a one-line error naming the candidates when that is unclear."""
    if units is not None:
        if units not in UNITS:
            raise ValueError(f"unknown units {units!r}; choose one of {', '.join(UNITS)}")
        return UNITS[units], units
    fits = [u for u, s in UNITS.items() if SIZE_RANGE[0] <= extent * s <= SIZE_RANGE[1]]
    if len(fits) == 1:
        return UNITS[fits[0]], fits[0]
    if not fits:
        raise ValueError(f"{name}: {extent:g} units across is no object's size in m, cm, mm or in; "
                         f"give --units")
    sizes = " or ".join(f"{extent * UNITS[u] * 100:.3g} cm ({u})" for u in fits)
    raise ValueError(f"{name}: units unclear, {extent:g} units across could be {sizes}; give --units")


def up_rotation(up: str) -> np.ndarray:
    """(3, 3) rotation taking the file's `up` axis to +z."""
    if up not in UP_AXES:
        raise ValueError(f"unknown up axis {up!r}; choose one of {', '.join(UP_AXES)}")
    sign = -1.0 if up.startswith("-") else 1.0
    a = sign * np.eye(3)["xyz".index(up[-1])]
    z = np.array([0.0, 0.0, 1.0])
    if np.allclose(a, z):
        return np.eye(3)
    if np.allclose(a, -z):
        return np.diag([1.0, -1.0, -1.0])  # half-turn about x
    axis = np.cross(a, z)
    return trimesh.transformations.rotation_matrix(np.pi / 2, axis)[:3, :3]


def footprint_centre(vertices: np.ndarray, band: float = FOOTPRINT) -> np.ndarray:
    """(2,) area centroid of the convex hull of the vertices (N, 3) within `band` of the lowest one."""
    low = vertices[vertices[:, 2] <= vertices[:, 2].min() + band][:, :2]
    if len(low) < 3:
        return low.mean(axis=0)
    try:
        from scipy.spatial import ConvexHull

        hull = low[ConvexHull(low).vertices]  # (H, 2), counter-clockwise
    except Exception:  # a degenerate (collinear) footprint
        return low.mean(axis=0)
    x, y = hull[:, 0], hull[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = cross.sum() / 2
    return np.array([((x + np.roll(x, -1)) * cross).sum(), ((y + np.roll(y, -1)) * cross).sum()]) / (6 * area)


def canonical_frame(mesh: trimesh.Trimesh, up: str = "z") -> trimesh.Trimesh:
    """A copy turned so `up` is +z, resting on z = 0, its footprint centred on the z axis."""
    out = mesh.copy()
    T = np.eye(4)
    T[:3, :3] = up_rotation(up)
    out.apply_transform(T)
    cx, cy = footprint_centre(np.asarray(out.vertices))
    out.apply_translation([-cx, -cy, -out.vertices[:, 2].min()])
    return out


def prepare_mesh(mesh: trimesh.Trimesh, units: str | None = None, up: str = "z", name: str = "mesh") -> PreparedMesh:
    """Repaired, metric and canonical (see the module's docstring), or a one-line error."""
    repaired, notes = repair(mesh, name)
    scale, units = metres_per_unit(float(repaired.extents.max()), units, name)
    size = float(repaired.extents.max()) * scale
    if not SIZE_RANGE[0] <= size <= SIZE_RANGE[1]:
        raise ValueError(f"{name}: {size * 100:.3g} cm across in {units}; a graspable object is "
                         f"{SIZE_RANGE[0] * 100:g}-{SIZE_RANGE[1] * 100:g} cm (check --units)")
    if scale != 1.0:
        repaired.apply_scale(scale)
        notes.append(f"scaled from {units} to metres (x{scale:g})")
    out = canonical_frame(repaired, up)
    if up != "z":
        notes.append(f"turned the file's {up} axis to +z")
    notes.append(f"placed on z = 0, footprint centred on the z axis; {out.extents[0] * 100:.1f} x "
                 f"{out.extents[1] * 100:.1f} x {out.extents[2] * 100:.1f} cm, {len(out.faces)} faces")
    return PreparedMesh(out, notes, scale, units)


def load_mesh(path: str | Path, upright: bool = False, units: str | None = "m", up: str = "z") -> trimesh.Trimesh:
    """A single watertight triangle mesh from a file (repaired as `repair` can), or a one-line error;
    with `upright=True` also scaled and put in the canonical frame (`prepare_mesh`)."""
    path = Path(path)
    raw = read_mesh(path)
    if upright:
        mesh = prepare_mesh(raw, units, up, path.name).mesh
    else:
        mesh, _ = repair(raw, path.name)
    mesh.metadata["name"] = path.stem
    return mesh
