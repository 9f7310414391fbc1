"""A fake RGB-D camera: depth frames ray-cast (Open3D) from the fake world and a table top at z = 0,
exact (no noise), in the pinhole model its intrinsics give."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import open3d as o3d
import trimesh

from hardware.fake.world import FakeWorld, NoLink
from hardware.interfaces import CameraIntrinsics, DepthCamera, Frame

TABLE = trimesh.creation.box((2.0, 2.0, 0.02), trimesh.transformations.translation_matrix([0.5, 0.0, -0.01]))


@dataclass(frozen=True)
class FakeCameraConfig:
    """Where the camera is (T_base_cam, OpenCV axes) and its intrinsics (a Kinect v2's depth camera)."""

    T_base_cam: np.ndarray = field(default_factory=lambda: np.eye(4))
    intrinsics: CameraIntrinsics = CameraIntrinsics(width=512, height=424, fx=365.456, fy=365.456, cx=254.878,
                                                    cy=205.395)


class FakeCamera(NoLink, DepthCamera):
    """A `DepthCamera` that renders the fake world as it is at each capture."""

    def __init__(self, world: FakeWorld, config: FakeCameraConfig = FakeCameraConfig()) -> None:
        super().__init__(config)
        self.world = world
        self.captures = 0

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return self.config.intrinsics

    def capture(self) -> Frame:
        """Depth along the optical axis (m, 0 where no surface), grey colour."""
        self.require_connected()
        K, T = self.intrinsics, self.config.T_base_cam
        scene = o3d.t.geometry.RaycastingScene()
        for mesh in [TABLE, *self.world.meshes()]:
            scene.add_triangles(o3d.core.Tensor(np.asarray(mesh.vertices, np.float32)),
                                o3d.core.Tensor(np.asarray(mesh.faces, np.uint32)))
        v, u = np.mgrid[0:K.height, 0:K.width]
        d_cam = np.stack([(u - K.cx) / K.fx, (v - K.cy) / K.fy, np.ones_like(u, float)], -1)  # (H, W, 3), z = 1
        d_base = d_cam @ T[:3, :3].T
        rays = np.concatenate([np.broadcast_to(T[:3, 3], d_base.shape), d_base], -1).astype(np.float32)
        t_hit = scene.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy()  # (H, W): along d, whose z is 1
        depth = np.where(np.isfinite(t_hit), t_hit, 0.0).astype(np.float32)
        self.captures += 1
        return Frame(np.full((K.height, K.width, 3), 128, np.uint8), depth, K, float(self.captures))
