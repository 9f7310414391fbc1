"""Simulated Kinect v2 behind the `DepthCamera` interface (PyBullet's CPU renderer + a noise model).

Depth: 512 x 424 with libfreenect2's default intrinsics, colour registered to depth (as
libfreenect2's `Registration` gives it), depth in metres along the optical axis, 0 = invalid.

Noise model (axial, per pixel; z in metres, theta = angle between the viewing ray and the surface
normal), after Nguyen et al. 2012 with Kinect v2-sized coefficients (Fankhauser et al. 2015 report
1-3 mm in this range):

    sigma(z, theta) = 0.0008 + 0.0012 (z - 0.5)^2 + 0.0001 / sqrt(z) * theta^2 / (pi/2 - theta)^2

then quantisation to 1 mm; pixels outside 0.5-4.5 m or with theta > 78 degrees (grazing) are
invalid. Not modelled: flying pixels at depth edges, multipath, colour noise.
The segmentation mask is kept as `last_segmentation` for tests; perception never reads it.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hardware.bullet import p
from hardware.interfaces import CameraIntrinsics, DepthCamera, Frame
from hardware.sim.world import SimWorld

KINECT_V2_DEPTH = CameraIntrinsics(width=512, height=424, fx=365.456, fy=365.456, cx=254.878, cy=205.395)
RANGE = (0.5, 4.5)  # metres
GRAZING_LIMIT = np.radians(78.0)
QUANTUM = 0.001  # metres
GL_NEAR, GL_FAR = 0.05, 6.0  # renderer clip planes, outside the valid range on both sides


@dataclass(frozen=True)
class NoiseModel:
    """Coefficients of sigma(z, theta) (metres); `enabled=False` gives exact depth (still quantised)."""

    base: float = 0.0008
    quadratic: float = 0.0012
    angular: float = 0.0001
    enabled: bool = True

    def sigma(self, z: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Axial standard deviation at depth z and incidence angle theta."""
        theta = np.minimum(theta, GRAZING_LIMIT)
        return (self.base + self.quadratic * (z - 0.5) ** 2
                + self.angular / np.sqrt(np.maximum(z, 1e-3)) * theta ** 2 / (np.pi / 2 - theta) ** 2)


@dataclass(frozen=True)
class SimKinectConfig:
    """Mounting pose (ground truth, the simulator's only), intrinsics and noise."""

    T_base_cam: tuple[tuple[float, ...], ...] = field(default_factory=lambda: tuple(map(tuple, np.eye(4))))
    intrinsics: CameraIntrinsics = KINECT_V2_DEPTH
    noise: NoiseModel = NoiseModel()
    seed: int = 0


def look_at(eye, target, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """T_base_cam of an OpenCV camera (x right, y down, z forward) at eye looking at target."""
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    z = target - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, up)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, y, z, eye
    return T


def gl_projection(K: CameraIntrinsics, near: float = GL_NEAR, far: float = GL_FAR) -> list[float]:
    """OpenGL projection matrix (column-major list) that reproduces pinhole intrinsics.

    OpenCV puts pixel centres at integer coordinates, OpenGL at half-integers: hence cx + 0.5.
    """
    W, H = K.width, K.height
    cx, cy = K.cx + 0.5, K.cy + 0.5
    P = np.array([
        [2 * K.fx / W, 0.0, 1.0 - 2 * cx / W, 0.0],
        [0.0, 2 * K.fy / H, 2 * cy / H - 1.0, 0.0],
        [0.0, 0.0, -(far + near) / (far - near), -2 * far * near / (far - near)],
        [0.0, 0.0, -1.0, 0.0],
    ])
    return P.T.flatten().tolist()


def gl_view(T_base_cam: np.ndarray) -> list[float]:
    """OpenGL view matrix (column-major list) of an OpenCV-convention camera pose."""
    T_cam_gl = np.diag([1.0, -1.0, -1.0, 1.0])  # GL camera looks down -z with y up
    view = np.linalg.inv(T_base_cam @ T_cam_gl)
    return view.T.flatten().tolist()


def incidence_angle(depth: np.ndarray, K: CameraIntrinsics) -> np.ndarray:
    """Angle between viewing ray and surface normal per pixel, from depth-image gradients."""
    v, u = np.mgrid[0:K.height, 0:K.width]
    rays = np.stack([(u - K.cx) / K.fx, (v - K.cy) / K.fy, np.ones_like(depth)], axis=-1)
    pts = rays * depth[..., None]  # (H, W, 3)
    du = np.gradient(pts, axis=1)
    dv = np.gradient(pts, axis=0)
    n = np.cross(du, dv)
    n /= np.linalg.norm(n, axis=-1, keepdims=True) + 1e-12
    r = rays / np.linalg.norm(rays, axis=-1, keepdims=True)
    return np.arccos(np.clip(np.abs(np.sum(n * r, axis=-1)), 0.0, 1.0))


class SimKinect(DepthCamera):
    """A Kinect v2 rendered in a SimWorld."""

    def __init__(self, config: SimKinectConfig, world: SimWorld) -> None:
        super().__init__(config)
        self.world = world
        self._rng = np.random.default_rng(config.seed)
        self.last_segmentation: np.ndarray | None = None
        self.T_base_cam = np.array(config.T_base_cam, dtype=np.float64)

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return self.config.intrinsics

    def reseed(self, seed: int | np.random.SeedSequence) -> None:
        """Restart the depth noise's random stream (the simulator's own: a job's seed then gives the
        same frames whatever the camera captured before, e.g. a calibration in the same process)."""
        self._rng = np.random.default_rng(seed)

    def _connect(self) -> None:
        self.world.connect()

    def _disconnect(self) -> None:
        pass

    def render_exact(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Noise-free (colour (H, W, 3) uint8, depth (H, W) metres, segmentation (H, W) body ids)."""
        self.require_connected()
        K = self.intrinsics
        _, _, rgba, zbuf, seg = p.getCameraImage(
            K.width, K.height, viewMatrix=gl_view(self.T_base_cam), projectionMatrix=gl_projection(K),
            renderer=p.ER_TINY_RENDERER, lightDirection=[0.6, -0.4, 1.0], shadow=0,
            flags=p.ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX, physicsClientId=self.world.require())
        rgba = np.asarray(rgba, dtype=np.uint8).reshape(K.height, K.width, 4)
        zbuf = np.asarray(zbuf, dtype=np.float64).reshape(K.height, K.width)
        depth = GL_FAR * GL_NEAR / (GL_FAR - (GL_FAR - GL_NEAR) * zbuf)
        depth[zbuf >= 1.0] = 0.0  # background
        seg = np.asarray(seg, dtype=np.int64).reshape(K.height, K.width)
        body = np.where(seg >= 0, seg & ((1 << 24) - 1), -1)
        return rgba[..., :3].copy(), depth, body

    def capture(self) -> Frame:
        color, depth, body = self.render_exact()
        theta = incidence_angle(depth, self.intrinsics)
        noisy = depth.copy()
        if self.config.noise.enabled:
            noisy += self._rng.normal(size=depth.shape) * self.config.noise.sigma(depth, theta)
        noisy = np.round(noisy / QUANTUM) * QUANTUM
        invalid = (depth <= 0) | (noisy < RANGE[0]) | (noisy > RANGE[1]) | (theta > GRAZING_LIMIT)
        noisy[invalid] = 0.0
        self.last_segmentation = body
        return Frame(color=color, depth=noisy.astype(np.float32), intrinsics=self.intrinsics,
                     timestamp=self.world.time)
