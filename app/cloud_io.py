"""Reading point clouds users hand us (PLY, PCD, XYZ via Open3D; .npy arrays), with one-line errors."""
from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import open3d as o3d

from app.io_utils import NPY_ERRORS

SUFFIXES = (".ply", ".pcd", ".xyz", ".npy")
# A cloud a task can use: enough distinct points for the imitation, an object's metric size (the
# test split's mugs, bowls and bottles span 6-35 cm; a cup-sized margin each way), within the UR5's
# reach of the base (0.85 m, with room for a calibration error)
MIN_POINTS = 16
EXTENT = (0.02, 0.8)  # m, the largest side of the cloud's bounding box
REACH = 1.2  # m from the base frame's origin to the cloud's centroid


@contextmanager
def c_output() -> Iterator[list[str]]:
    """Inside the block, what C libraries write to stdout and stderr (Open3D's reader and its RPly
    print their own messages) is caught; the list holds its lines, colour codes removed, after it."""
    import re
    import sys
    import tempfile

    lines: list[str] = []
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile(mode="w+b") as sink:
        os.dup2(sink.fileno(), 1)
        os.dup2(sink.fileno(), 2)
        try:
            yield lines
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            sink.seek(0)
            text = re.sub(r"\x1b\[[0-9;]*m", "", sink.read().decode(errors="replace"))
            lines += [line.strip() for line in text.splitlines() if line.strip()]


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
        except NPY_ERRORS as exc:
            raise ValueError(f"{path} is not a readable .npy array ({exc})") from None
    else:
        with c_output() as said:
            cloud = np.asarray(o3d.io.read_point_cloud(str(path)).points)
        if problem := next((line for line in said if "fail" in line.lower() or "error" in line.lower()), None):
            raise ValueError(f"{path}: not a readable {suffix[1:].upper()} cloud ({problem})")
    cloud = np.asarray(cloud, dtype=np.float64)
    if cloud.ndim != 2 or cloud.shape[1] != 3:
        raise ValueError(f"{path}: a cloud must be N x 3, got shape {cloud.shape}")
    if len(cloud) == 0:
        raise ValueError(f"{path}: the point cloud is empty")
    if not np.isfinite(cloud).all():
        raise ValueError(f"{path}: the point cloud contains NaN or inf")
    return cloud


def check_cloud(cloud: np.ndarray, name: str = "the cloud") -> np.ndarray:
    """The cloud (N, 3) if an object cloud in metres in the base frame could be it, else a one-line
    ValueError naming what is wrong: too few distinct points, millimetres (or another unit), a size
    no object has, or a place beyond the arm's reach."""
    distinct = len(np.unique(np.round(cloud, 6), axis=0))
    if distinct < MIN_POINTS:
        raise ValueError(f"{name} has {distinct} distinct points; imitation needs at least {MIN_POINTS}")
    extent = float((cloud.max(axis=0) - cloud.min(axis=0)).max())
    if extent > EXTENT[1]:
        if EXTENT[0] <= extent / 1000 <= EXTENT[1]:
            raise ValueError(f"{name} spans {extent:.4g} units, an object {extent / 1000:.3f} m across if they are "
                             f"millimetres: give the cloud in metres")
        raise ValueError(f"{name} spans {extent:.3g} m; an object cloud spans {EXTENT[0]}-{EXTENT[1]} m (metres expected)")
    if extent < EXTENT[0]:
        raise ValueError(f"{name} spans {extent * 1000:.1f} mm; an object cloud spans {EXTENT[0]}-{EXTENT[1]} m "
                         f"(metres expected)")
    distance = float(np.linalg.norm(cloud.mean(axis=0)))
    if distance > REACH:
        raise ValueError(f"{name} lies {distance:.2f} m from the robot's base, beyond the cell's {REACH} m "
                         f"(is it in the base frame?)")
    return cloud


def save_cloud(path: str | Path, cloud: np.ndarray) -> Path:
    """Write a PLY atomically."""
    from app.io_utils import atomic_path

    with atomic_path(path) as tmp:
        ply = tmp.with_suffix(".ply")
        o3d.io.write_point_cloud(str(ply), o3d.geometry.PointCloud(o3d.utility.Vector3dVector(cloud)))
        ply.replace(tmp)
    return Path(path)
