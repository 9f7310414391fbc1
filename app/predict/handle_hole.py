"""Find a mug's handle hole in its cloud (our addition, not in the paper): where the peg must go.

The imitated hang pins the hole well across the peg but poorly along the vertical, the rack's tight
direction: the hole is 2-3.5 cm wide across, less the peg's 12 mm, so a hang ends 4-12 mm from a
miss, and imitated places left the hole 14-95 mm off the peg (docs/jobs.md). The cloud shows the
hole's geometry directly whenever it shows the handle:

1. the body's axis a: the direction most perpendicular to the surface normals n_i (a body of
   revolution's normals all cross its axis), the eigenvector of the smallest eigenvalue of
   sum_i n_i n_i^T;
2. the body's surface of revolution: in the plane across a, the circle of centre c whose radius
   changes linearly along the axis, rho(h) = r_0 + k h, fitted robustly to all points
   (residual e_i = |p_i - c| - rho(h_i), a soft-L1 loss: the handle's points are outliers), from
   the algebraic circle's start; when that fit is no body (a view of one side is a shallow arc,
   and the start can lie on its wrong side), from circles all around the points, keeping the fit
   with the most points on it;
3. the handle: the points e_i > HANDLE_OFFSET outside the body, at azimuth phi (their circular
   mean); the hole's height h_c is the middle of their height span, and the tube's outer edge
   rho_out the farthest of them within BAND of h_c;
4. the hole's centre on that azimuth, at HOLE_FRACTION of the way from the body's surface to the
   tube's outer edge: rho = rho(h_c) + f (rho_out - rho(h_c)).
   (The generator's hole lies midway between the wall and the tube's inner edge,
   f = 1/2 - r_tube / (reach + r_tube) ~ 0.34 for its handles; `app.objects.handle.hole_center`.)

The hole's frame: x the radial direction to the handle, z the body's axis (towards the rim, which
the caller names), y = z x x the hole's axis - the frame `app.objects` puts a mug's handle in.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d
from scipy.optimize import least_squares

from hardware.se3 import make_pose


@dataclass(frozen=True)
class HoleConfig:
    """The detector's settings (metres, radians)."""

    normal_neighbors: int = 20  # points per normal estimate
    fit_scale: float = 0.002  # m: residuals beyond this count less in the body's fit (soft L1)
    handle_offset: float = 0.008  # m outside the body's surface where the handle starts
    min_handle_points: int = 8  # fewer handle points than this: no handle seen
    sector: float = 0.4  # rad either side of the handle's azimuth that belong to it
    band: float = 0.01  # m about the hole's height where the tube's outer edge is read
    hole_fraction: float = 0.34  # of the way from the body's surface to the tube's outer edge
    outer_depth: float = 0.006  # m: handle points this close to the farthest are its outer face
    radius_range: tuple[float, float] = (0.02, 0.08)  # m: a fit that ends on a bound found no body
    min_on_body: float = 0.4  # of the points must lie within fit_scale of the body's surface
    snap: float = 0.35  # rad: an axis this close to the table's normal (`up`) is taken to be it
    restart_radii: tuple[float, ...] = (0.03, 0.045, 0.06)  # m: the refit's starting radii (`refit_body`)
    restart_azimuths: int = 8  # starting centres per radius, around the points' centroid


@dataclass(frozen=True)
class Hole:
    """A handle hole seen in a cloud: its frame in the cloud's frame, and the handle's point count."""

    T: np.ndarray  # (4, 4): origin the hole's centre, x radial to the handle, y the hole's axis, z the body's
    handle_points: int


def body_axis(points: np.ndarray, neighbors: int) -> np.ndarray:
    """(3,) unit axis of a body of revolution: the direction most perpendicular to its normals."""
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(neighbors))
    n = np.asarray(pcd.normals)  # (M, 3)
    return np.linalg.eigh(n.T @ n)[1][:, 0]


def across(axis: np.ndarray) -> np.ndarray:
    """(3, 2) an orthonormal basis of the plane across `axis`."""
    u = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    return np.column_stack([u, np.cross(axis, u)])


def body_residuals(x: np.ndarray, flat: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(M,) how far each point - in-plane coordinates `flat` (M, 2), height h (M,) - lies outside the
    body x = (c_u, c_v, r_0, k): a circle about (c_u, c_v) of radius r_0 + k h."""
    return np.linalg.norm(flat - x[:2], axis=1) - (x[2] + x[3] * h)


def kasa_circle(flat: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre (2,) and radius of the algebraic (Kasa) least-squares circle through points (M, 2):
    |p|^2 = 2 c.p + (r^2 - |c|^2), linear in c and r^2 - |c|^2; an arc is enough."""
    A = np.column_stack([2 * flat, np.ones(len(flat))])
    sol = np.linalg.lstsq(A, (flat ** 2).sum(axis=1), rcond=None)[0]
    return sol[:2], float(np.sqrt(max(sol[2] + sol[:2] @ sol[:2], 0.0)))


def fit_body_from(flat: np.ndarray, h: np.ndarray, config: "HoleConfig", centre: np.ndarray,
                  radius: float) -> np.ndarray:
    """The body x (`body_residuals`) fitted with a soft-L1 loss (the handle's points are outliers),
    radius bounded to config.radius_range, from a circle of `centre` (2,) and `radius`."""
    lo, hi = config.radius_range
    c = centre if np.linalg.norm(centre) < hi else np.zeros(2)
    bounds = ([-hi, -hi, lo, -1.0], [hi, hi, hi, 1.0])
    start = np.clip([*c, float(np.clip(radius, lo, hi)), 0.0], bounds[0], bounds[1])
    return least_squares(body_residuals, start, args=(flat, h), bounds=bounds, loss="soft_l1",
                         f_scale=config.fit_scale).x


def fit_body(flat: np.ndarray, h: np.ndarray, config: "HoleConfig") -> np.ndarray:
    """The body x fitted from an algebraic circle's start (`kasa_circle`)."""
    return fit_body_from(flat, h, config, *kasa_circle(flat))


def on_body(x: np.ndarray, flat: np.ndarray, h: np.ndarray, config: "HoleConfig") -> float:
    """The fraction of the points within config.fit_scale of the body x's surface."""
    return float((np.abs(body_residuals(x, flat, h)) < config.fit_scale).mean())


def fits(x: np.ndarray, flat: np.ndarray, h: np.ndarray, config: "HoleConfig") -> bool:
    """Whether the body x is one: its radius inside the range (not on a bound) and enough points on it."""
    lo, hi = config.radius_range
    return lo < x[2] < hi and on_body(x, flat, h, config) >= config.min_on_body


def refit_body(flat: np.ndarray, h: np.ndarray, config: "HoleConfig") -> np.ndarray:
    """The body x with the most points on it among fits started from circles around the points'
    centroid (config.restart_radii x config.restart_azimuths): a view of one side of a body is a
    shallow arc, whose algebraic circle can lie on the wrong side of it."""
    mid = flat.mean(axis=0)
    turns = np.linspace(0.0, 2 * np.pi, config.restart_azimuths, endpoint=False)
    fitted = [fit_body_from(flat, h, config, mid + r * np.array([np.cos(a), np.sin(a)]), r)
              for r in config.restart_radii for a in turns]
    return max(fitted, key=lambda x: on_body(x, flat, h, config))


def find_hole(points: np.ndarray, toward: np.ndarray, config: HoleConfig = HoleConfig(),
              up: np.ndarray | None = None) -> Hole | None:
    """The handle hole of a mug's cloud (M, 3), its frame's z towards the point `toward` (the rim's
    side: a rim grasp's TCP); None when the cloud shows too little of a handle."""
    points = np.asarray(points, float)
    if len(points) < 3 * config.normal_neighbors:
        return None
    mean = points.mean(axis=0)
    q = points - mean  # (M, 3)
    axis = body_axis(points, config.normal_neighbors)
    if up is not None and abs(axis @ up) > np.cos(config.snap):
        axis = np.asarray(up, float) / np.linalg.norm(up)  # standing on the table: its axis is the table's normal
    if (np.asarray(toward, float) - mean) @ axis < 0:
        axis = -axis
    B = across(axis)  # (3, 2)
    flat, h = q @ B, q @ axis  # (M, 2), (M,)
    x = fit_body(flat, h, config)
    if not fits(x, flat, h, config):
        x = refit_body(flat, h, config)
        if not fits(x, flat, h, config):
            return None  # no body of revolution fits: the handle cannot be told from the rest
    res, rel, base = body_residuals(x, flat, h), flat - x[:2], B @ x[:2]  # (M,), (M, 2) from the axis, (3,)
    out = res > config.handle_offset  # the handle's points
    if out.sum() < config.min_handle_points:
        return None
    rim = out & (res > res[out].max() - config.outer_depth)  # the tube's outer face
    ang = np.arctan2(rel[:, 1], rel[:, 0])
    phi = np.arctan2(np.sin(ang[rim]).mean(), np.cos(ang[rim]).mean())
    mine = out & (np.abs(np.angle(np.exp(1j * (ang - phi)))) < config.sector)
    if mine.sum() < config.min_handle_points:
        return None
    face = mine & (res > res[mine].max() - config.outer_depth)  # (M,) the tube's outer face
    hc = (h[mine].min() + h[mine].max()) / 2
    surface = x[2] + x[3] * hc  # the body's radius at the hole's height
    depth = np.median(res[face])  # the tube's outer edge beyond the body's surface
    radial = B @ [np.cos(phi), np.sin(phi)]  # (3,)
    centre = mean + base + (surface + config.hole_fraction * depth) * radial + hc * axis
    R = np.column_stack([radial, np.cross(axis, radial), axis])
    return Hole(make_pose(R, centre), int(mine.sum()))
