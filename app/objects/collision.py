"""Collision models for PyBullet: approximate convex decomposition with CoACD, cached on disk.

CoACD (collision-aware concavity, Wei et al. 2022) keeps a mug's handle hole and its cavity open,
which V-HACD at usable resolutions tends to fill. The parts are written as one OBJ with an `o`
block per convex part; PyBullet's `createCollisionShape(GEOM_MESH, fileName=...)` loads such a
file as a compound of convex hulls.
"""
from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import trimesh

from app.io_utils import atomic_path, cache_root


@dataclass(frozen=True)
class DecompositionConfig:
    """CoACD settings: about 100 parts and 12 s per mug; handle holes and thin walls survive."""

    threshold: float = 0.02  # concavity threshold x bbox diagonal ~ max surface error (0.05 let bowl rims slip)
    resolution: int = 2000  # sampling resolution of the concavity metric
    mcts_iterations: int = 60
    mcts_depth: int = 2
    mcts_nodes: int = 15
    seed: int = 0


def cache_dir() -> Path:
    """Where collision models are cached: $NIFT_CACHE/collision or ~/.cache/nift-cell/collision."""
    return cache_root() / "collision"


def _key(mesh: trimesh.Trimesh, config: DecompositionConfig) -> str:
    h = hashlib.sha1()
    h.update(np.ascontiguousarray(mesh.vertices, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(mesh.faces, dtype=np.int64).tobytes())
    h.update(repr(config).encode())
    return h.hexdigest()[:20]


DECOMPOSE_TIMEOUT = 600.0  # s: CoACD longer than this is stopped (the slowest of our objects takes about 60 s)


def decompose(mesh: trimesh.Trimesh, config: DecompositionConfig = DecompositionConfig(),
              timeout: float = DECOMPOSE_TIMEOUT) -> list[trimesh.Trimesh]:
    """Convex parts whose union approximates the mesh (CoACD, in a child process: CoACD keeps about
    6 MB of every decomposition for the life of its process, which a cell meeting new objects all
    day would pile up; docs/limits.md, "Soak"); a one-line error when it runs over `timeout` s."""
    if not mesh.is_watertight:
        raise ValueError("convex decomposition needs a watertight mesh")
    with tempfile.TemporaryDirectory(prefix="nift-coacd-") as tmp:
        source, parts = Path(tmp) / "mesh.npz", Path(tmp) / "parts.obj"
        np.savez(source, vertices=np.asarray(mesh.vertices, float), faces=np.asarray(mesh.faces, np.int64))
        code_root = str(Path(__file__).resolve().parents[2])  # the child imports this same code
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [code_root, os.environ.get("PYTHONPATH")]))}
        try:
            done = subprocess.run([sys.executable, "-m", "app.objects.collision", str(source), str(parts),
                                   json.dumps(asdict(config)), str(os.getpid())], env=env, capture_output=True,
                                  text=True, timeout=timeout)
        except subprocess.TimeoutExpired:  # subprocess.run has killed the child
            raise RuntimeError(f"CoACD's convex decomposition ran over {timeout:.0f} s on {len(mesh.faces)} faces and "
                               f"was stopped; try fewer faces (--collision-faces)") from None
        if done.returncode != 0:
            last = (done.stderr.strip().splitlines() or ["no message"])[-1]
            raise RuntimeError(f"CoACD's convex decomposition failed (exit {done.returncode}): {last}")
        return read_parts_obj(parts)


def run_coacd(mesh: trimesh.Trimesh, config: DecompositionConfig = DecompositionConfig()) -> list[trimesh.Trimesh]:
    """CoACD's convex parts of a watertight mesh, in this process (`decompose` runs it in a child)."""
    import coacd

    coacd.set_log_level("error")
    parts = coacd.run_coacd(
        coacd.Mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
        threshold=config.threshold, resolution=config.resolution, preprocess_mode="off",
        mcts_iterations=config.mcts_iterations, mcts_max_depth=config.mcts_depth,
        mcts_nodes=config.mcts_nodes, seed=config.seed,
    )
    return [trimesh.Trimesh(v, f, process=False).convex_hull for v, f in parts]


def _decompose_here(source: Path, out: Path, config: DecompositionConfig) -> None:
    """The child's side of `decompose`: CoACD's convex parts of the mesh in `source` (.npz), as an OBJ."""
    with np.load(source, allow_pickle=False) as data:
        mesh = trimesh.Trimesh(data["vertices"], data["faces"], process=False)
    write_parts_obj(run_coacd(mesh, config), out)


def write_parts_obj(parts: list[trimesh.Trimesh], path: str | Path) -> Path:
    """Write convex parts as one OBJ, one `o` block each (atomically)."""
    lines, offset = [], 1
    for i, part in enumerate(parts):
        lines.append(f"o part{i}")
        lines += [f"v {x:.7f} {y:.7f} {z:.7f}" for x, y, z in part.vertices]
        lines += [f"f {a + offset} {b + offset} {c + offset}" for a, b, c in part.faces]
        offset += len(part.vertices)
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    return Path(path)


def read_parts_obj(path: str | Path) -> list[trimesh.Trimesh]:
    """Read the convex parts back from an OBJ written by `write_parts_obj`."""
    parts, verts, faces, offset = [], [], [], 0

    def flush():
        if faces:
            parts.append(trimesh.Trimesh(np.array(verts[offset:]), np.array(faces) - offset - 1, process=False))

    for line in Path(path).read_text().splitlines():
        if line.startswith("o "):
            flush()
            offset, faces = len(verts), []
        elif line.startswith("v "):
            verts.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            faces.append([int(x.split("/")[0]) for x in line.split()[1:4]])
    flush()
    return parts


def collision_model(mesh: trimesh.Trimesh, config: DecompositionConfig = DecompositionConfig()) -> Path:
    """Path of a cached OBJ of the mesh's convex decomposition, computing it on first use."""
    path = cache_dir() / f"{_key(mesh, config)}.obj"
    if not path.exists():
        write_parts_obj(decompose(mesh, config), path)
    return path


def visual_model(mesh: trimesh.Trimesh) -> Path:
    """Path of a cached OBJ of the mesh itself (PyBullet's visual shape), written on first use."""
    path = cache_dir() / f"{_key(mesh, DecompositionConfig())}-visual.obj"
    if not path.exists():
        write_parts_obj([mesh], path)
    return path


if __name__ == "__main__":  # the child process of `decompose`: SOURCE.npz OUT.obj CONFIG-JSON PARENT-PID
    from app.workers import die_with_parent

    die_with_parent(int(sys.argv[4]))  # a command killed with SIGKILL leaves no decomposition running
    _decompose_here(Path(sys.argv[1]), Path(sys.argv[2]), DecompositionConfig(**json.loads(sys.argv[3])))
