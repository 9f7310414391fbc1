"""Spatial Context Features (SCF, Zhao et al. 2016; NIFT Eq. 2-4) by Embree ray casting.

For a point x, rays are cast in K fixed directions; d(w) is the hit distance (inf on a miss) and

    F_x(w) = (d_min + d_avg) / (d(w) + d_avg)      (Eq. 2; F = 0 where the ray misses)

with d_min, d_avg the minimum and mean of the finite distances. F is projected on the real,
orthonormal spherical harmonics Y_l^m (l <= n) by quadrature,

    c_l^m = sum_k w_k F(w_k) Y_l^m(w_k)            (Eq. 3, a (K, (n+1)^2) matrix product)

and the SCF is the power per band, c_l = sqrt(sum_m (c_l^m)^2), l = 0..n   (Eq. 4).

Directions and weights are a Lebedev rule (SciPy): DEFAULT_DEGREE = 53 gives K = 974 near-uniform
directions whose quadrature is exact for polynomials up to degree 53, so the basis is exactly
orthonormal for n <= 26. F itself is not band-limited (it jumps at silhouettes), so the discrete
sampling still costs accuracy: against a 5,810-direction rule (degree 131), the SCF (n = 5) of
points around our objects differs by a median 0.9 % and a 95th percentile of about 3 % of |SCF|
(`nift bench-geometry` re-measures this as `scf_direction_error`).

Normalisation: with orthonormal Y, a constant F = 1 has c_0 = sqrt(4 pi) = 3.5449 and c_l = 0 for
l >= 1 - that is the SCF at the centre of a closed sphere.

Invariances: translation and scale (F uses distance ratios) exactly; rotation up to the
quadrature error above (band powers are rotation invariant, the discrete direction set is not).

Points inside a closed mesh are allowed: their rays hit the inner side of the surface and the SCF
is computed the same way (no rays escape, so F > 0 everywhere). Tell inside from outside with
occupancy, not with the SCF. A point that hits nothing at all gets SCF = 0.

Point clouds (single-view input, the "SCF" baseline): `compute_scf_cloud` replaces each point by
a hexagonal surfel (a disk of radius `splat_scale` x the mean nearest-neighbour spacing, oriented
by the PCA normal) and ray casts that surfel soup the same way. On clouds sampled from the whole
surface it agrees with the mesh SCF (see `nift bench-geometry`, `scf_cloud_r2`).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.integrate import lebedev_rule
from scipy.spatial import cKDTree
from scipy.special import sph_harm_y
from threadpoolctl import threadpool_limits

from app.nift.raycast import cast, make_scene, scene_of

DEFAULT_ORDER = 5
DEFAULT_DEGREE = 53  # Lebedev degree -> 974 directions
CHUNK_RAYS = 1_000_000  # rays per Embree call (24 MB of rays, reused across chunks)


@dataclass(frozen=True)
class SphericalBasis:
    """Quadrature directions and the weighted real SH matrix for one (order, degree)."""

    order: int
    directions: np.ndarray  # (K, 3) unit vectors, float32
    weights: np.ndarray  # (K,) quadrature weights, sum = 4 pi
    projector: np.ndarray  # (K, (n+1)^2): weights[:, None] * Y_real, so coeffs = F @ projector
    band_sum: np.ndarray  # ((n+1)^2, n+1) one-hot: squared coefficients @ band_sum = band powers


def real_sph_harm(order: int, directions: np.ndarray) -> np.ndarray:
    """Real orthonormal spherical harmonics Y_l^m at unit directions: (K, 3) -> (K, (order+1)^2).

    Columns are ordered l = 0..order, m = -l..l; built from SciPy's complex `sph_harm_y`
    (Y_l^m real = sqrt(2) Im Y_l^|m| for m < 0, Y_l^0, sqrt(2) Re Y_l^m for m > 0).
    """
    x, y, z = directions.T
    polar = np.arccos(np.clip(z, -1.0, 1.0))
    azimuth = np.arctan2(y, x)
    columns = []
    for l in range(order + 1):
        for m in range(-l, l + 1):
            Y = sph_harm_y(l, abs(m), polar, azimuth)
            if m < 0:
                columns.append(np.sqrt(2.0) * Y.imag)
            elif m == 0:
                columns.append(Y.real)
            else:
                columns.append(np.sqrt(2.0) * Y.real)
    return np.stack(columns, axis=1)


@lru_cache(maxsize=16)
def spherical_basis(order: int = DEFAULT_ORDER, degree: int = DEFAULT_DEGREE) -> SphericalBasis:
    """The cached Lebedev directions and SH projector for an SCF order."""
    if order < 0:
        raise ValueError(f"SCF order must be >= 0, got {order}")
    if degree < 2 * order:
        raise ValueError(f"Lebedev degree {degree} cannot integrate SH products of order {order}")
    points, weights = lebedev_rule(degree)
    directions = points.T.astype(np.float32)
    Y = real_sph_harm(order, directions.astype(np.float64))
    band = np.concatenate([np.full(2 * l + 1, l) for l in range(order + 1)])
    band_sum = (band[:, None] == np.arange(order + 1)[None]).astype(np.float32)
    projector = (weights[:, None] * Y).astype(np.float32)
    return SphericalBasis(order, directions, weights, projector, band_sum)


def spherical_function(d: np.ndarray) -> np.ndarray:
    """Eq. 2: hit distances (N, K) float32 (inf = miss) -> F (N, K), overwriting d.

    Misses need no mask: (d_min + d_avg) / (inf + d_avg) = 0. Rows with no hit get F = 0.
    This runs on every ray, so it makes few passes and no copies.
    """
    finite = np.isfinite(d)
    n_hit = np.count_nonzero(finite, axis=1)[:, None]  # (N, 1)
    d_avg = np.sum(d, axis=1, where=finite, keepdims=True) / np.maximum(n_hit, 1)
    num = np.where(n_hit > 0, d.min(axis=1, keepdims=True) + d_avg, 0.0).astype(d.dtype)
    np.add(d, d_avg, out=d)
    np.divide(num, d, out=d)
    return d


def band_powers(F: np.ndarray, basis: SphericalBasis) -> np.ndarray:
    """Eq. 3-4: F (N, K) -> SCF (N, n+1), c_l = sqrt(sum_m (c_l^m)^2)."""
    coeffs = F @ basis.projector  # (N, (n+1)^2)
    return np.sqrt((coeffs * coeffs) @ basis.band_sum)  # (N, n+1)


def _scf_in_scene(scene, points: np.ndarray, basis: SphericalBasis) -> np.ndarray:
    """SCF of points in an Embree scene, cast in chunks of CHUNK_RAYS rays."""
    points = np.asarray(points, dtype=np.float32)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"query points must be (N, 3), got shape {points.shape}")
    if not np.isfinite(points).all():
        raise ValueError("query points contain NaN or inf")
    K = len(basis.directions)
    chunk = max(1, CHUNK_RAYS // K)
    out = np.empty((len(points), basis.order + 1), dtype=np.float32)
    rays = np.empty((chunk, K, 6), dtype=np.float32)
    rays[:, :, 3:] = basis.directions[None]
    # One BLAS thread: OpenBLAS's idle threads spin after each matmul and slow Embree's own
    # threads by about a third on a 2-core machine (measured); the projection is small anyway.
    with threadpool_limits(1, user_api="blas"):
        for start in range(0, len(points), chunk):
            p = points[start:start + chunk]
            r = rays[:len(p)]
            r[:, :, :3] = p[:, None, :]
            d = cast(scene, r.reshape(-1, 6)).reshape(len(p), K)
            out[start:start + len(p)] = band_powers(spherical_function(d), basis)
    return out


def compute_scf(mesh, points: np.ndarray, order: int = DEFAULT_ORDER, degree: int = DEFAULT_DEGREE) -> np.ndarray:
    """SCF of query points (N, 3) w.r.t. a mesh (trimesh or an Open3D scene): (N, order + 1)."""
    return _scf_in_scene(scene_of(mesh), points, spherical_basis(order, degree))


def surfel_mesh(cloud: np.ndarray, splat_scale: float = 1.5, k_normal: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Hexagonal surfels for a cloud (M, 3): (vertices (7M, 3), faces (6M, 3)).

    Each point becomes a flat hexagon perpendicular to its PCA normal (k_normal neighbours), with
    radius splat_scale x the cloud's mean nearest-neighbour spacing.
    """
    cloud = np.asarray(cloud, dtype=np.float64)
    if cloud.ndim != 2 or cloud.shape[1] != 3 or len(cloud) < k_normal:
        raise ValueError(f"a point cloud needs at least {k_normal} points of 3 coordinates, got shape {cloud.shape}")
    if not np.isfinite(cloud).all():
        raise ValueError("point cloud contains NaN or inf")
    tree = cKDTree(cloud)
    dist, idx = tree.query(cloud, k=k_normal)
    spacing = float(np.mean(dist[:, 1]))
    nbrs = cloud[idx] - cloud[idx].mean(axis=1, keepdims=True)  # (M, k, 3)
    _, _, vt = np.linalg.svd(nbrs, full_matrices=False)
    normal = vt[:, 2]  # (M, 3) direction of least variance
    helper = np.where(np.abs(normal[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(normal, u)
    angles = np.arange(6) * np.pi / 3
    radius = splat_scale * spacing
    ring = cloud[:, None] + radius * (np.cos(angles)[None, :, None] * u[:, None] + np.sin(angles)[None, :, None] * v[:, None])
    vertices = np.concatenate([cloud[:, None], ring], axis=1).reshape(-1, 3)  # (7M, 3)
    base = (np.arange(len(cloud)) * 7)[:, None, None]
    local = np.array([[0, 1 + i, 1 + (i + 1) % 6] for i in range(6)])
    faces = (base + local[None]).reshape(-1, 3)
    return vertices, faces


def compute_scf_cloud(cloud: np.ndarray, points: np.ndarray, order: int = DEFAULT_ORDER,
                      degree: int = DEFAULT_DEGREE, splat_scale: float = 1.5) -> np.ndarray:
    """SCF of query points (N, 3) w.r.t. a point cloud (M, 3), by ray casting surfels: (N, order + 1)."""
    vertices, faces = surfel_mesh(cloud, splat_scale)
    return _scf_in_scene(make_scene(vertices, faces), points, spherical_basis(order, degree))
