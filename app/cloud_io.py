"""Reading point clouds users hand us (PLY, PCD, XYZ via Open3D; .npy arrays), with one-line errors."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import open3d as o3d

SUFFIXES = (".ply", ".pcd", ".xyz", ".npy")


def load_cloud(path: str | Path) -> np.ndarray:
    """An (N, 3) float64 cloud from a file; refuses missing files, unknown formats, empty or NaN clouds."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no point cloud at {path}")
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise ValueError(f"{path}: unknown point cloud format {suffix!r}; use one of {', '.join(SUFFIXES)}")
    if suffix == ".npy":
        try:
            cloud = np.load(path, allow_pickle=False)
        except ValueError as exc:
            raise ValueError(f"{path} is not a readable .npy array ({exc})") from None
    else:
        cloud = np.asarray(o3d.io.read_point_cloud(str(path)).points)
    cloud = np.asarray(cloud, dtype=np.float64)
    if cloud.ndim != 2 or cloud.shape[1] != 3:
        raise ValueError(f"{path}: a cloud must be N x 3, got shape {cloud.shape}")
    if len(cloud) == 0:
        raise ValueError(f"{path}: the point cloud is empty")
    if not np.isfinite(cloud).all():
        raise ValueError(f"{path}: the point cloud contains NaN or inf")
    return cloud


def save_cloud(path: str | Path, cloud: np.ndarray) -> Path:
    """Write a PLY atomically."""
    from app.io_utils import atomic_path

    with atomic_path(path) as tmp:
        ply = tmp.with_suffix(".ply")
        o3d.io.write_point_cloud(str(ply), o3d.geometry.PointCloud(o3d.utility.Vector3dVector(cloud)))
        ply.replace(tmp)
    return Path(path)
