"""Make one solid of a downloaded mesh: split it into pieces, close what can be closed, drop what
encloses nothing, and take the union of what is left (manifold3d).

Downloaded meshes are rarely one closed surface. A scan carries zero-volume slivers and small
islands beside its body; a modelled mug's handle is an open-ended tube sunk into the body; parts
overlap; a flap of triangles hangs off an edge (a non-manifold fan). `solidify` handles them in
one way:

1. split the triangles into pieces joined only through manifold edges (an edge of exactly two
   faces), so a fin on an edge, or two bodies that share an edge, come apart;
2. close each piece: trimesh's hole filling for small holes, then each remaining boundary loop
   capped by a fan from its centroid (the open end of a tube), then MeshFix;
3. drop pieces that still cannot be closed or that enclose less than `DROPPED_VOLUME` of the
   largest (slivers, flaps, scan debris), and say how many faces went;
4. the union of the closed pieces (manifold3d's exact booleans), then the largest connected body
   of it: islands that touch nothing are dropped too.

What is left is refused only when nothing encloses a volume: one line says why.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

DROPPED_VOLUME = 0.02  # a closed piece enclosing less than this share of the largest piece's volume is debris
FLAT = 1e-6  # a closed piece enclosing less than this times its largest extent cubed is flat: it encloses nothing


@dataclass(frozen=True)
class Piece:
    """One closed piece, or why it could not be one."""

    mesh: trimesh.Trimesh
    closed: bool
    how: str = ""  # how it was closed ("" when it was closed already)


class NotASolid(ValueError):
    """Nothing in the mesh encloses a volume, even after repair."""


def manifold_pieces(mesh: trimesh.Trimesh) -> list[trimesh.Trimesh]:
    """The mesh split into pieces whose faces are joined only through edges shared by exactly two faces."""
    adjacency = mesh.face_adjacency  # (P, 2) pairs of faces sharing an edge of exactly two faces
    counts = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
    nonmanifold = {tuple(e) for e, c in zip(*counts) if c > 2}
    if nonmanifold:
        edges = [tuple(e) for e in np.sort(mesh.face_adjacency_edges, axis=1)]
        adjacency = adjacency[[e not in nonmanifold for e in edges]]
    groups = trimesh.graph.connected_components(adjacency, nodes=np.arange(len(mesh.faces)), min_len=1)
    return [_submesh(mesh, g) for g in sorted(groups, key=len, reverse=True)]


def _submesh(mesh: trimesh.Trimesh, faces: np.ndarray) -> trimesh.Trimesh:
    out = trimesh.Trimesh(mesh.vertices, mesh.faces[np.sort(faces)], process=False)
    out.remove_unreferenced_vertices()
    return out


def boundary_loops(mesh: trimesh.Trimesh) -> list[np.ndarray]:
    """The open boundary as closed loops of vertex indices (each edge used by one face only)."""
    open_rows = trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1)
    edges = mesh.edges[open_rows]  # directed as their face has them
    following = {int(a): int(b) for a, b in edges}
    loops, seen = [], set()
    for start in following:
        if start in seen:
            continue
        loop, v = [], start
        while v not in seen and v in following:
            seen.add(v)
            loop.append(v)
            v = following[v]
        if v == start and len(loop) >= 3:
            loops.append(np.array(loop))
    return loops


def capped(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """A copy with every boundary loop closed by a fan of triangles from the loop's centroid."""
    vertices, faces = [np.asarray(mesh.vertices, float)], [np.asarray(mesh.faces)]
    count = len(mesh.vertices)
    for loop in boundary_loops(mesh):
        vertices.append(mesh.vertices[loop].mean(axis=0, keepdims=True))
        ring = np.column_stack([np.roll(loop, -1), loop, np.full(len(loop), count)])  # opposite to the open edge
        faces.append(ring)
        count += 1
    out = trimesh.Trimesh(np.vstack(vertices), np.vstack(faces), process=False)
    out.merge_vertices()
    return out


def close_piece(piece: trimesh.Trimesh) -> Piece:
    """The piece closed and facing outwards: as it is, with holes filled, capped, or by MeshFix."""
    attempts = (("", lambda m: m), ("holes filled", _filled), ("open ends capped", capped), ("MeshFix", _meshfix))
    for how, step in attempts:
        out = step(piece.copy())
        if out is not None and out.is_watertight and out.is_winding_consistent:
            with np.errstate(divide="ignore", invalid="ignore"):  # a flat piece's centre of mass divides by 0
                trimesh.repair.fix_normals(out)
                encloses = out.volume > FLAT * out.extents.max() ** 3
            if encloses:
                return Piece(out, True, how)
    return Piece(piece, False)


def _filled(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    trimesh.repair.fill_holes(mesh)
    return mesh


def _meshfix(mesh: trimesh.Trimesh) -> trimesh.Trimesh | None:
    """MeshFix's closing of the piece, None when it leaves nothing (it keeps the largest component)."""
    from pymeshfix import MeshFix

    if len(mesh.faces) < 4:
        return None
    fix = MeshFix(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int32))
    fix.repair(remove_smallest_components=False)
    points, faces = np.asarray(fix.points), np.asarray(fix.faces)
    if not len(faces):
        return None
    out = trimesh.Trimesh(points, faces, process=True)
    return out if (out.extents >= 0.9 * mesh.extents).all() else None  # it dropped a part of the piece


def to_manifold(mesh: trimesh.Trimesh):
    """A closed trimesh as a manifold3d solid."""
    import manifold3d as m3d

    return m3d.Manifold(m3d.Mesh(vert_properties=np.asarray(mesh.vertices, np.float32),
                                 tri_verts=np.asarray(mesh.faces, np.uint32)))


def union(parts: list[trimesh.Trimesh]) -> trimesh.Trimesh:
    """The exact boolean union of closed parts (manifold3d)."""
    import manifold3d as m3d

    solids = [to_manifold(p) for p in parts]
    whole = m3d.Manifold.batch_boolean(solids, m3d.OpType.Add) if len(solids) > 1 else solids[0]
    out = whole.to_mesh()
    return trimesh.Trimesh(np.asarray(out.vert_properties[:, :3], float), np.asarray(out.tri_verts), process=True)


def solidify(mesh: trimesh.Trimesh, name: str = "mesh") -> tuple[trimesh.Trimesh, list[str]]:
    """One watertight, outward-facing solid from the mesh (see the module's docstring) and what was
    done; NotASolid when no piece encloses a volume."""
    notes: list[str] = []
    pieces = [close_piece(p) for p in manifold_pieces(mesh)]
    closed = [p for p in pieces if p.closed]
    if not closed:
        raise NotASolid(f"{name}: no part of it encloses a volume ({len(mesh.faces)} faces, "
                        f"{_open_edges(mesh)} open edges); it cannot be a solid object")
    largest = max(p.mesh.volume for p in closed)
    kept = [p for p in closed if p.mesh.volume >= DROPPED_VOLUME * largest]
    dropped = [p for p in pieces if all(p is not k for k in kept)]
    if dropped:
        faces = sum(len(p.mesh.faces) for p in dropped)
        notes.append(f"dropped {len(dropped)} piece(s) that enclose no volume of note (slivers, flaps, "
                     f"islands: {faces} faces)")
    for how in sorted({p.how for p in kept if p.how}):
        notes.append(f"closed {sum(p.how == how for p in kept)} piece(s): {how}")
    if len(kept) == 1:
        return kept[0].mesh, notes
    whole = union([p.mesh for p in kept])
    bodies = whole.split(only_watertight=True)
    body = max(bodies, key=lambda b: b.volume) if len(bodies) else whole
    notes.append(f"took the union of {len(kept)} overlapping parts (manifold3d)")
    if len(bodies) > 1:
        notes.append(f"dropped {len(bodies) - 1} part(s) that touch nothing else "
                     f"({sum(b.volume for b in bodies) - body.volume:.3g} units^3)")
    return body, notes


def _open_edges(mesh: trimesh.Trimesh) -> int:
    return len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))
