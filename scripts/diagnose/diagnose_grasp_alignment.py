"""How far grasp alignment turns the scripted teacher's (square) grasps, by where the normals come from:
the mesh itself (its face normals), four fused cameras, or the cell's one Kinect (docs/additions.md, "Grasp alignment").

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_grasp_alignment.py TASK POSE TRIAL... [--seed 0]
e.g. `bowl upright 0-8` (about 1 s per trial). The trials are `nift bench`'s: the same objects, poses
and clouds. A teacher grasp closes square to the rim's wall, so every degree of turn is an error of
the normals; the bench aligns grasps where this stays small (fused) and not where it does not (single).
"""
import argparse

import numpy as np
import trimesh

from app.bench.protocol import BenchConfig, Trial, parse_indices
from app.bench.trial import TeleportedBench
from app.predict.grasp_alignment import align_grasp
from app.predict.grasp_centering import swept_mask
from app.tasks.task import task, teacher_grasp

SOURCES = ("mesh", "fused", "single")


def turn_degrees(T: np.ndarray, cloud: np.ndarray, normals: np.ndarray | None = None) -> float:
    """Angle (degrees) the closing axis turns onto the normals' wall axis (no cap); NaN: nothing between the fingers."""
    if not swept_mask(T, cloud).any():
        return float("nan")
    y = align_grasp(T, cloud, normals, max_angle=np.pi / 2)[:3, 1]
    return float(np.degrees(np.arccos(np.clip(y @ T[:3, 1], -1.0, 1.0))))


def trial_turns(bench: TeleportedBench, t, pose: str, index: int, seed: int) -> dict[str, float]:
    """The teacher grasp's turn on each source's normals for one bench trial."""
    seen = {camera: bench.observe(Trial(t.name, pose, index), camera, seed) for camera in ("single", "fused")}
    obj, T_base_obj, _ = seen["single"]  # the same object and pose in both: drawn before the cloud
    T = T_base_obj @ teacher_grasp(obj.mesh)
    posed = obj.mesh.copy().apply_transform(T_base_obj)
    points, faces = trimesh.sample.sample_surface(posed, 4096, seed=index)
    return {"mesh": turn_degrees(T, points, posed.face_normals[faces]),
            **{camera: turn_degrees(T, cloud) for camera, (_, _, cloud) in seen.items()}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("task")
    parser.add_argument("pose")
    parser.add_argument("trials", nargs="+")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    config = BenchConfig(tasks=(args.task,), seed=args.seed)
    bench = TeleportedBench(config.cell)
    t = task(args.task)
    rows = []
    for i in parse_indices(args.trials):
        turns = trial_turns(bench, t, args.pose, i, args.seed)
        rows.append([turns[s] for s in SOURCES])
        print(f"{t.name} {args.pose} {i}: " + "  ".join(f"{s} {turns[s]:5.1f}" for s in SOURCES), flush=True)
    table = np.array(rows)  # (trials, sources)
    for s, column in zip(SOURCES, table.T):
        done = column[np.isfinite(column)]
        if len(done):
            print(f"{s:>6}: median {np.median(done):.1f}, max {done.max():.1f} degrees over {len(done)} grasps")


if __name__ == "__main__":
    main()
