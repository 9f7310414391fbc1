"""Meshes that look like a user's scans, made from our procedural objects: texture seams (vertices
stored once per UV island), decimation, noise, small holes, millimetres, another up axis."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh
from PIL import Image


def decimated(mesh: trimesh.Trimesh, faces: int) -> trimesh.Trimesh:
    """Open3D's quadric decimation to about `faces` triangles (it may open the surface)."""
    import open3d as o3d

    o3 = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(mesh.vertices), o3d.utility.Vector3iVector(mesh.faces))
    small = o3.simplify_quadric_decimation(target_number_of_triangles=faces)
    return trimesh.Trimesh(np.asarray(small.vertices), np.asarray(small.triangles), process=False)


def with_seams(mesh: trimesh.Trimesh, islands: int = 6) -> trimesh.Trimesh:
    """Each face's vertices duplicated per UV island (angular sectors about z), with cylindrical UVs:
    the surface is open along every island border until seam vertices are merged."""
    centres = mesh.triangles_center
    sector = ((np.arctan2(centres[:, 1], centres[:, 0]) + np.pi) / (2 * np.pi) * islands).astype(int) % islands
    vertices, faces, uv = [], [], []
    for k in range(islands):
        tri = mesh.faces[sector == k]
        used, inverse = np.unique(tri, return_inverse=True)
        v = mesh.vertices[used]
        offset = sum(len(x) for x in vertices)
        vertices.append(v)
        faces.append(inverse.reshape(-1, 3) + offset)
        angle = (np.arctan2(v[:, 1], v[:, 0]) + np.pi) / (2 * np.pi)
        uv.append(np.column_stack([(k + angle) / islands, v[:, 2] / max(np.ptp(mesh.vertices[:, 2]), 1e-9)]))
    texture = trimesh.visual.TextureVisuals(uv=np.vstack(uv), image=Image.new("RGB", (8, 8), (180, 120, 90)))
    return trimesh.Trimesh(np.vstack(vertices), np.vstack(faces), visual=texture, process=False)


def with_holes(mesh: trimesh.Trimesh, holes: int, rng: np.random.Generator) -> trimesh.Trimesh:
    """The mesh with `holes` single faces removed (small holes, as a scanner leaves)."""
    keep = np.ones(len(mesh.faces), bool)
    keep[rng.choice(len(mesh.faces), holes, replace=False)] = False
    out = mesh.copy()
    out.update_faces(keep)
    return out


def scan_like(mesh: trimesh.Trimesh, path: Path, faces: int = 3000, noise: float = 3e-4, holes: int = 4,
              units: float = 1000.0, up: str = "z", seed: int = 0) -> Path:
    """Write `mesh` (metres, z up) as a scan would come: decimated, noisy, holed, seamed, in `units`
    per metre, with `up` ("z" or "y") up."""
    rng = np.random.default_rng(seed)
    out = decimated(mesh, faces) if faces else mesh.copy()
    out = trimesh.Trimesh(out.vertices + rng.normal(0, noise, out.vertices.shape), out.faces, process=False)
    out = with_holes(out, holes, rng) if holes else out
    if up == "y":
        out.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))
    out = with_seams(out)
    out.apply_scale(units)
    out.export(path)
    return path
