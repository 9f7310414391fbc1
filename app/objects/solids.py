"""Solid-modelling primitives for the procedural objects, built on manifold3d.

manifold3d guarantees manifold (watertight, self-intersection-free) results for revolves, hulls
and booleans, which is what ray casting (SCF), occupancy labels and convex decomposition need.
"""
from __future__ import annotations

import numpy as np
import trimesh
from manifold3d import CrossSection, JoinType, Manifold, OpType

SEGMENTS = 64  # circular segments of every body of revolution


def revolve(profile_rz: np.ndarray, segments: int = SEGMENTS) -> Manifold:
    """Solid of revolution about +z from a closed (r, z) polygon with r >= 0: (K, 2) -> Manifold."""
    profile_rz = np.asarray(profile_rz, dtype=np.float64)
    if profile_rz.ndim != 2 or profile_rz.shape[1] != 2 or len(profile_rz) < 3:
        raise ValueError(f"a profile is a (K>=3, 2) array of (r, z), got shape {profile_rz.shape}")
    section = CrossSection([profile_rz])
    return Manifold.revolve(section, circular_segments=segments)


def tube(path: np.ndarray, radius: float, segments: int = 24,
         squash: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> Manifold:
    """A tube along a 3-D polyline: union of the convex hulls of consecutive ball pairs; `squash`
    scales the balls along x, y, z (a flat strap in the x-z plane: thin in x and z, wide in y)."""
    ball = Manifold.sphere(radius, segments).scale(tuple(squash))
    balls = [ball.translate(tuple(p)) for p in np.asarray(path, float)]
    links = [Manifold.batch_hull([a, b]) for a, b in zip(balls[:-1], balls[1:])]
    return Manifold.batch_boolean(links, OpType.Add)


def to_trimesh(solid: Manifold) -> trimesh.Trimesh:
    """Manifold -> trimesh.Trimesh (float64 vertices, watertight as manifold3d made it)."""
    mesh = solid.to_mesh()
    vertices = np.asarray(mesh.vert_properties, dtype=np.float64)[:, :3]
    faces = np.asarray(mesh.tri_verts, dtype=np.int64)
    # process=False: merging near-coincident vertices would break the manifold topology
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)


def closed_profile(z: np.ndarray, r_outer: np.ndarray) -> np.ndarray:
    """Closed (r, z) polygon of a solid whose outer radius at height z[i] is r_outer[i]."""
    z = np.asarray(z, float)
    r_outer = np.asarray(r_outer, float)
    outline = np.stack([r_outer, z], axis=1)
    axis = np.array([[0.0, z[-1]], [0.0, z[0]]])
    return np.concatenate([outline, axis])


def _mirrored_section(z: np.ndarray, r: np.ndarray) -> CrossSection:
    """Full (both sides of the axis) cross-section of a solid with radius r(z), counter-clockwise."""
    right = np.stack([r, z], axis=1)
    left = np.stack([-r[::-1], z[::-1]], axis=1)
    return CrossSection([np.concatenate([right, left])])


def _band(z_lo: float, z_hi: float, half_width: float) -> CrossSection:
    """The horizontal strip z_lo <= z <= z_hi, |r| <= half_width, as a cross-section."""
    return CrossSection.square((2 * half_width, z_hi - z_lo)).translate((-half_width, z_lo))


def hollow(z: np.ndarray, r_outer: np.ndarray, wall: float, bottom: float,
           segments: int = SEGMENTS) -> tuple[Manifold, Manifold]:
    """An open-topped vessel of revolution: (body, cavity) solids.

    The outer surface has radius r_outer(z) for z in [0, z[-1]]; the inner surface is the outer one
    offset inwards by `wall` along the normal (Clipper2 offset, so the wall thickness is uniform
    whatever the slope), the floor is `bottom` thick (bottom >= wall), and the top is open.
    The cavity is returned too, so that parts added outside (a handle) can be cut back from it.
    """
    z = np.asarray(z, float)
    r_outer = np.asarray(r_outer, float)
    if bottom < wall:
        raise ValueError(f"bottom thickness {bottom} must be >= wall thickness {wall}")
    height, reach = z[-1], 2.0 * float(r_outer.max()) + 1.0
    extra = height + 3.0 * wall + 0.01  # continue the wall straight up so the cavity opens the top
    outer = _mirrored_section(np.append(z, extra), np.append(r_outer, r_outer[-1]))
    inner = outer.offset(-wall, JoinType.Round, circular_segments=32)
    cavity = inner ^ _band(bottom, extra + 1.0, reach)
    body = (outer ^ _band(0.0, height, reach)) - cavity
    return (Manifold.revolve(body, circular_segments=segments),
            Manifold.revolve(cavity, circular_segments=segments))
