"""Deliberately broken meshes, as downloads come, each with the solid it was meant to be.

Each maker returns (broken mesh, intended solid); sizes are a mug's, in metres."""
from __future__ import annotations

import numpy as np
import trimesh
from shapely.geometry import Point

BODY_RADIUS, BODY_HEIGHT = 0.04, 0.10


def body() -> trimesh.Trimesh:
    """A closed cylinder standing on z = 0."""
    out = trimesh.creation.cylinder(BODY_RADIUS, BODY_HEIGHT, sections=48)
    out.apply_translation([0, 0, BODY_HEIGHT / 2])
    return out


def handle(cap: bool) -> trimesh.Trimesh:
    """A tube (radius 6 mm) along a half circle outside the body's side whose two ends are 1 cm inside it;
    open-ended unless `cap`."""
    t = np.linspace(-np.pi / 2, np.pi / 2, 24)
    reach = 0.035
    path = np.column_stack([BODY_RADIUS - 0.01 + reach * np.cos(t), np.zeros_like(t), 0.05 + reach * np.sin(t)])
    return trimesh.creation.sweep_polygon(Point(0, 0).buffer(0.006, 8), path, cap=cap)


def joined(*meshes: trimesh.Trimesh) -> trimesh.Trimesh:
    """The meshes' triangles in one mesh, nothing merged or repaired."""
    return trimesh.util.concatenate(list(meshes))


def slivers_beside_a_body() -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A closed body with zero-volume sliver triangles beside it (some touching its vertices)."""
    b = body()
    v = b.vertices
    slivers = trimesh.Trimesh(np.vstack([v[:3], v[:3] + [0.0005, 0, 0], [[0.06, 0, 0.02], [0.061, 0, 0.02],
                                                                             [0.0605, 0.00001, 0.05]]]),
                              [[0, 1, 3], [1, 2, 4], [6, 7, 8]], process=False)
    return joined(b, slivers), b


def open_handle_sunk_in_a_body() -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A modelled mug: a closed body and a separate open-ended handle tube sunk into it."""
    from app.objects.mesh_repair import union

    return joined(body(), handle(cap=False)), union([body(), handle(cap=True)])


def two_overlapping_parts() -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """Two closed parts that overlap (a body and a thick lid sunk 1 cm into it)."""
    from app.objects.mesh_repair import union

    lid = trimesh.creation.cylinder(BODY_RADIUS * 0.8, 0.03, sections=40)
    lid.apply_translation([0.01, 0, BODY_HEIGHT + 0.005])
    return joined(body(), lid), union([body(), lid])


def flipped_normals(seed: int = 0) -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A closed body with a random third of its faces wound the wrong way."""
    b = body()
    faces = b.faces.copy()
    flip = np.random.default_rng(seed).random(len(faces)) < 1 / 3
    faces[flip] = faces[flip][:, ::-1]
    return trimesh.Trimesh(b.vertices, faces, process=False), b


def small_hole() -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A closed body with three adjacent side triangles missing."""
    b = body()
    side = np.flatnonzero(np.abs(b.face_normals[:, 2]) < 0.1)
    first = side[0]
    near = side[np.argsort(np.linalg.norm(b.triangles_center[side] - b.triangles_center[first], axis=1))[:3]]
    keep = np.ones(len(b.faces), bool)
    keep[near] = False
    return trimesh.Trimesh(b.vertices, b.faces[keep], process=False), b


def nonmanifold_fan() -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A closed body with a fan of four zero-thickness triangles hung on one of its edges (that edge is
    shared by six faces)."""
    b = body()
    radial = np.linalg.norm(b.vertices[b.edges_unique][:, :, :2], axis=2).min(axis=1)  # (E,)
    a, c = b.edges_unique[np.flatnonzero(radial > BODY_RADIUS / 2)[0]]  # an edge on the rim, off the axis
    mid = (b.vertices[a] + b.vertices[c]) / 2
    out = b.vertices[a] - [0, 0, 0]
    outward = np.append(out[:2] / np.linalg.norm(out[:2]), 0.0)
    tips = [mid + 0.02 * (outward * np.cos(k) + np.array([0, 0, 1.0]) * np.sin(k)) for k in (0.2, 0.6, 1.0, 1.4)]
    n = len(b.vertices)
    fan = [[a, c, n + i] for i in range(len(tips))]
    return trimesh.Trimesh(np.vstack([b.vertices, tips]), np.vstack([b.faces, fan]), process=False), b


def open_sheet() -> trimesh.Trimesh:
    """A flat 5 x 5 grid of triangles, 10 cm across: no solid object."""
    x, y = np.meshgrid(np.linspace(0, 0.1, 6), np.linspace(0, 0.1, 6))
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(36)])
    cells = [(i * 6 + j, i * 6 + j + 1, (i + 1) * 6 + j + 1, (i + 1) * 6 + j) for i in range(5) for j in range(5)]
    faces = [f for a, b, c, d in cells for f in ((a, b, c), (a, c, d))]
    return trimesh.Trimesh(vertices, faces, process=False)


BROKEN = {
    "slivers beside a closed body": slivers_beside_a_body,
    "an open-ended handle tube sunk into a body": open_handle_sunk_in_a_body,
    "two overlapping closed parts": two_overlapping_parts,
    "flipped normals": flipped_normals,
    "a hole of a few triangles": small_hole,
    "a non-manifold fan": nonmanifold_fan,
}
