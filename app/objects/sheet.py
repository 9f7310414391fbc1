"""Contact sheets: shaded views of many instances in one PNG, so a person can see the variety.

Rendering is Open3D ray casting (CPU, no OpenGL context needed on a headless machine) with
Lambert shading from the hit normals.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import open3d as o3d
import trimesh

from app.nift.raycast import scene_of

LIGHT = np.array([0.4, -0.5, 0.75]) / np.linalg.norm([0.4, -0.5, 0.75])
BACKGROUND = np.array([1.0, 1.0, 1.0])
BASE_COLOUR = np.array([0.55, 0.68, 0.85])


def render_mesh(mesh: trimesh.Trimesh, size: int = 256, elevation_deg: float = 25.0,
                azimuth_deg: float = -60.0) -> np.ndarray:
    """Shaded image of a mesh seen from a camera on a sphere around it: (size, size, 3) float in [0, 1]."""
    centre = mesh.bounds.mean(axis=0)
    radius = float(np.linalg.norm(mesh.extents)) / 2
    el, az = np.radians(elevation_deg), np.radians(azimuth_deg)
    direction = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    fov = 30.0
    eye = centre + direction * radius / np.sin(np.radians(fov / 2)) * 1.05
    rays = o3d.t.geometry.RaycastingScene.create_rays_pinhole(
        fov_deg=fov, center=centre.tolist(), eye=eye.tolist(), up=[0, 0, 1], width_px=size, height_px=size)
    hits = scene_of(mesh).cast_rays(rays)
    hit = np.isfinite(hits["t_hit"].numpy())
    normals = hits["primitive_normals"].numpy()
    view = rays.numpy()[..., 3:]
    normals = np.where((np.sum(normals * view, axis=-1) > 0)[..., None], -normals, normals)  # face the camera
    shade = 0.25 + 0.75 * np.clip(normals @ LIGHT, 0.0, 1.0)
    image = np.where(hit[..., None], shade[..., None] * BASE_COLOUR, BACKGROUND)
    return image[::-1, ::-1]  # Open3D's pinhole rays come out rotated by 180 degrees


def contact_sheet(meshes: list[trimesh.Trimesh], labels: list[str], out: str | Path,
                  columns: int = 4, size: int = 256) -> Path:
    """Render meshes in a grid with a label under each and write a PNG (atomically)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from app.io_utils import atomic_path

    rows = int(np.ceil(len(meshes) / columns))
    fig, axes = plt.subplots(rows, columns, figsize=(2.2 * columns, 2.4 * rows), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, mesh, label in zip(axes.flat, meshes, labels):
        ax.imshow(render_mesh(mesh, size))
        ax.set_title(label, fontsize=8)
    fig.tight_layout()
    out = Path(out)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)
    return out
