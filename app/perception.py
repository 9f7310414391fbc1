"""One RGB-D frame -> the object's point cloud in the robot base frame (Open3D for the geometry).

Steps: back-project the valid depth pixels with the intrinsics and the (calibrated) camera pose,
crop to the workspace box, remove the table plane (RANSAC) and the points on known fixtures (their
meshes at their poses), keep the largest DBSCAN cluster, remove statistical outliers, then resample
to a fixed point count (farthest point sampling).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import open3d as o3d
import trimesh

from app.failures import BadFrame, ObjectNotSeen
from app.nift.raycast import scene_of, unsigned_distance
from hardware.gripper_geometry import GripperGeometry
from hardware.interfaces import Frame
from hardware.settings import check_integers, check_ranges


DEPTH_MAX = 10.0  # m: farther depth pixels are dropped


@dataclass(frozen=True)
class PerceptionConfig:
    """Workspace crop (base frame, metres) and the segmentation parameters."""

    x_range: tuple[float, float] = (0.28, 0.80)
    y_range: tuple[float, float] = (-0.26, 0.28)
    z_range: tuple[float, float] = (-0.03, 0.40)
    plane_threshold: float = 0.006  # RANSAC inlier distance
    above_plane: float = 0.004  # points closer than this to the table plane are table
    cluster_eps: float = 0.015
    cluster_min_points: int = 20
    outlier_neighbors: int = 20
    outlier_std_ratio: float = 2.0
    n_points: int = 1024
    seed: int = 0
    known_margin: float = 0.015  # m: points this near a known fixture's surface are the fixture (noise: a few mm)

    def __post_init__(self) -> None:
        check_integers(self, ("cluster_min_points", "outlier_neighbors", "n_points", "seed"))
        check_ranges(self, (("plane_threshold", 0.0, 0.1, "m", False), ("above_plane", 0.0, 0.1, "m", True),
                            ("cluster_eps", 0.0, 0.5, "m", False), ("cluster_min_points", 1, 100_000, "", True),
                            ("outlier_neighbors", 1, 1000, "", True), ("outlier_std_ratio", 0.0, 100.0, "", False),
                            ("n_points", 16, 1_000_000, "", True), ("known_margin", 0.0, 0.5, "m", True)))
        for name in ("x_range", "y_range", "z_range"):
            low, high = getattr(self, name)
            if not low < high:
                raise ValueError(f"{name} must be a range (low, high) with low < high, got {getattr(self, name)!r}")


def back_project(frame: Frame, T_base_cam: np.ndarray) -> np.ndarray:
    """Valid depth pixels as points in the base frame, in the image's row-major order: (M, 3).

    A pixel (u, v) of depth z is the camera-frame point ((u - cx) z / fx, (v - cy) z / fy, z)."""
    depth = np.asarray(frame.depth)
    K = frame.intrinsics
    if depth.shape != (K.height, K.width):
        raise BadFrame(f"depth image is {depth.shape}, intrinsics say {(K.height, K.width)}")
    if np.isnan(depth).any():
        raise BadFrame("depth image contains NaN (a driver should report invalid depth as 0)")
    if not (depth > 0).any():
        raise BadFrame("depth image has no valid pixel (all 0)")
    # numpy, not Open3D's create_from_depth_image: that one returns the same points in a thread-timing
    # order, and farthest point sampling, RANSAC and DBSCAN downstream follow the order - a seed's job
    # was not the same twice in a process (docs/decisions.md, "Back-projection in pixel order")
    rows, cols = np.nonzero((depth > 0) & (depth <= DEPTH_MAX))  # row-major: the image's own order
    z = depth[rows, cols].astype(np.float64)
    cam = np.stack([(cols - K.cx) * z / K.fx, (rows - K.cy) * z / K.fy, z], axis=1)  # (M, 3) camera frame
    return cam @ T_base_cam[:3, :3].T + T_base_cam[:3, 3]


def crop(points: np.ndarray, cfg: PerceptionConfig) -> np.ndarray:
    """Points inside the workspace box."""
    lo = np.array([cfg.x_range[0], cfg.y_range[0], cfg.z_range[0]])
    hi = np.array([cfg.x_range[1], cfg.y_range[1], cfg.z_range[1]])
    return points[np.all((points >= lo) & (points <= hi), axis=1)]


def remove_table(points: np.ndarray, cfg: PerceptionConfig) -> np.ndarray:
    """Drop the dominant near-horizontal plane and everything within `above_plane` of it."""
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    o3d.utility.random.seed(cfg.seed)
    (a, b, c, d), _ = pcd.segment_plane(cfg.plane_threshold, 3, 500)
    normal = np.array([a, b, c])
    if abs(normal[2]) < 0.9 * np.linalg.norm(normal):
        return points  # no table in view: the largest plane is something else
    if c < 0:
        normal, d = -normal, -d
    height = (points @ normal + d) / np.linalg.norm(normal)
    return points[height > cfg.above_plane]


def largest_cluster(points: np.ndarray, cfg: PerceptionConfig) -> np.ndarray:
    """The biggest DBSCAN cluster."""
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    labels = np.asarray(pcd.cluster_dbscan(cfg.cluster_eps, cfg.cluster_min_points))
    if (labels < 0).all():
        raise ObjectNotSeen("no object in the workspace (no cluster after removing the table)")
    biggest = np.bincount(labels[labels >= 0]).argmax()
    return points[labels == biggest]


def resample(points: np.ndarray, n: int, seed: int) -> np.ndarray:
    """Exactly n points: farthest point sampling down, random repeats up."""
    if len(points) >= n:
        pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
        return np.asarray(pcd.farthest_point_down_sample(n).points)
    extra = np.random.default_rng(seed).choice(len(points), n - len(points))
    return np.concatenate([points, points[extra]])


def off_known(points: np.ndarray, known: Sequence[trimesh.Trimesh], margin: float) -> np.ndarray:
    """The points (M, 3) farther than `margin` (m) from every known surface (meshes in the base frame):
    what is left once a fixture the cell knows is taken out of the view."""
    if not known or len(points) == 0:
        return points
    d = unsigned_distance(scene_of(trimesh.util.concatenate(list(known))), points)  # (M,) to the nearest surface
    return points[d > margin]


def object_points(frame: Frame, T_base_cam: np.ndarray, cfg: PerceptionConfig = PerceptionConfig(),
                  known: Sequence[trimesh.Trimesh] = ()) -> np.ndarray:
    """All the object's points (M, 3) in the base frame, before resampling, or a one-line PerceptionFailure;
    points on the `known` meshes (base frame: fixtures in view) are left out."""
    points = crop(back_project(frame, T_base_cam), cfg)
    if len(points) == 0:
        raise ObjectNotSeen("no object in the workspace (no depth point inside the workspace box)")
    points = off_known(remove_table(points, cfg), known, cfg.known_margin)
    if len(points) < cfg.cluster_min_points:
        raise ObjectNotSeen("no object in the workspace (only the table is visible)")
    points = largest_cluster(points, cfg)
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd, _ = pcd.remove_statistical_outlier(cfg.outlier_neighbors, cfg.outlier_std_ratio)
    return np.asarray(pcd.points)


def object_cloud(frame: Frame, T_base_cam: np.ndarray, cfg: PerceptionConfig = PerceptionConfig()) -> np.ndarray:
    """The object's cloud (cfg.n_points, 3) in the base frame, or a one-line PerceptionFailure."""
    return resample(object_points(frame, T_base_cam, cfg), cfg.n_points, cfg.seed)


def held_object_cloud(frame: Frame, T_base_cam: np.ndarray, T_base_tcp: np.ndarray, width: float, near: np.ndarray,
                      radius: float, cfg: PerceptionConfig = PerceptionConfig(),
                      geometry: GripperGeometry = GripperGeometry(), margin: float = 0.01) -> np.ndarray:
    """The points (M, 3), base frame, of an object held in the gripper at T_base_tcp: those within
    `radius` of `near` (where the object should be), less the gripper's own (its boxes at the TCP
    pose, fingers `width` apart, grown by `margin`), the largest cluster, outliers removed; a
    one-line PerceptionFailure when nothing is left."""
    points = back_project(frame, T_base_cam)
    points = points[np.linalg.norm(points - near, axis=1) < radius]
    local = (points - T_base_tcp[:3, 3]) @ T_base_tcp[:3, :3]  # (M, 3) TCP frame
    points = points[~geometry.contains(local, width, margin)]
    if len(points) < cfg.cluster_min_points:
        raise ObjectNotSeen(f"the held object is not in view ({len(points)} points near it)")
    points = largest_cluster(points, cfg)
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd, _ = pcd.remove_statistical_outlier(cfg.outlier_neighbors, cfg.outlier_std_ratio)
    return np.asarray(pcd.points)
