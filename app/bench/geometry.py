"""Geometry benchmark: Embree ray rate, SCF throughput and accuracy, IBS time and accuracy.

Every figure is measured here, on this machine, by `nift bench-geometry`; timings are the best
of `repeats` runs so that a busy moment does not decide the number.
"""
from __future__ import annotations

import os
import time
from typing import Callable

import numpy as np

from app.nift.ibs import compute_ibs
from app.nift.raycast import cast, make_scene, signed_distance, unsigned_distance, view_cloud
from app.nift.scf import CHUNK_RAYS, compute_scf, compute_scf_cloud, spherical_basis
from app.objects import generate, rack
from hardware.se3 import make_pose, random_rotations


def best_time(fn: Callable[[], object], repeats: int) -> float:
    """Fastest wall time of `repeats` calls, seconds."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def query_box(mesh, n: int, rng: np.random.Generator, outside: bool = False) -> np.ndarray:
    """n points uniform in the box 1.5 x the mesh's bounding box (optionally only outside it)."""
    lo, hi = mesh.bounds
    c, h = (lo + hi) / 2, (hi - lo) * 0.75
    pts = rng.uniform(c - h, c + h, size=(4 * n if outside else n, 3))
    if outside:
        pts = pts[signed_distance(make_scene(mesh.vertices, mesh.faces), pts) > 0.003][:n]
    return pts


def relative_error(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-row |a - b| / |b|."""
    return np.linalg.norm(a - b, axis=1) / np.maximum(np.linalg.norm(b, axis=1), 1e-12)


def r2_per_band(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """Coefficient of determination per column."""
    ss_res = ((pred - true) ** 2).sum(axis=0)
    ss_tot = ((true - true.mean(axis=0)) ** 2).sum(axis=0)
    return 1.0 - ss_res / ss_tot


def ray_benchmark(mesh, n_points: int, repeats: int, rng: np.random.Generator) -> dict:
    """Raw Embree rate on the SCF's own ray pattern vs the SCF's effective rate."""
    basis = spherical_basis()
    K = len(basis.directions)
    scene = make_scene(mesh.vertices, mesh.faces)
    pts = query_box(mesh, n_points, rng).astype(np.float32)
    cast(scene, np.zeros((1000, 6), np.float32) + [0, 0, 0, 0, 0, 1])  # warm up Embree's BVH
    raw = 0.0  # the best rate over batch sizes: the SCF's own chunk and a large batch
    for m in (max(1, CHUNK_RAYS // K), 2048):
        m = min(m, len(pts))
        rays = np.concatenate([np.repeat(pts[:m], K, axis=0), np.tile(basis.directions, (m, 1))], axis=1)
        raw = max(raw, len(rays) / best_time(lambda: cast(scene, rays), repeats))
    scf_pps = len(pts) / best_time(lambda: compute_scf(scene, pts), repeats)
    return {"directions": K, "raw_mrays_per_s": raw / 1e6, "scf_points_per_s": scf_pps,
            "scf_effective_mrays_per_s": scf_pps * K / 1e6, "scf_fraction_of_raw": scf_pps * K / raw}


def scf_accuracy(mesh, n_points: int, rng: np.random.Generator) -> dict:
    """Quadrature error (vs 5,810 directions), rotation invariance error, cloud-vs-mesh R^2."""
    pts = query_box(mesh, n_points, rng)
    ref = compute_scf(mesh, pts, degree=131)
    ours = compute_scf(mesh, pts)
    direction_err = relative_error(ours, ref)
    R = random_rotations(1, rng)[0]
    T = make_pose(R, rng.uniform(-0.5, 0.5, 3))
    moved = mesh.copy()
    moved.apply_transform(T)
    rot_err = relative_error(compute_scf(moved, pts @ R.T + T[:3, 3]), ours)
    outside = query_box(mesh, n_points, rng, outside=True)
    cloud = mesh.sample(3000, seed=int(rng.integers(1 << 31)))
    true = compute_scf(mesh, outside)
    r2 = r2_per_band(compute_scf_cloud(cloud, outside), true)
    centre = mesh.bounds.mean(axis=0)
    seen = view_cloud(make_scene(mesh.vertices, mesh.faces), centre + [0.5, -0.5, 0.35], centre)
    r2_single = r2_per_band(compute_scf_cloud(seen, outside), true)
    return {
        "scf_direction_error_median": float(np.median(direction_err)),
        "scf_direction_error_p95": float(np.percentile(direction_err, 95)),
        "scf_rotation_error_median": float(np.median(rot_err)),
        "scf_rotation_error_p95": float(np.percentile(rot_err, 95)),
        "scf_cloud_r2_per_band": [float(x) for x in r2],
        "scf_cloud_r2_mean": float(r2.mean()),
        "scf_single_view_points": len(seen),
        "scf_single_view_r2_per_band": [float(x) for x in r2_single],
        "scf_single_view_r2_mean": float(r2_single.mean()),
    }


def ibs_benchmark(repeats: int, n_samples: int = 2000, n_points: int = 1000) -> dict:
    """IBS between a mug and the rack: time, and the equidistance gap in units of sample spacing."""
    mug = generate("mug", 1)
    fixture = rack().mesh.copy()
    fixture.apply_translation([0.2, 0.0, -0.15])
    result = compute_ibs(mug, fixture, n_points=n_points, n_samples=n_samples)
    seconds = best_time(lambda: compute_ibs(mug, fixture, n_points=n_points, n_samples=n_samples), repeats)
    gap = np.abs(unsigned_distance(make_scene(mug.vertices, mug.faces), result.points)
                 - unsigned_distance(make_scene(fixture.vertices, fixture.faces), result.points))
    return {"ibs_seconds": seconds, "ibs_samples_per_object": n_samples, "ibs_query_points": n_points,
            "ibs_gap_max_mm": float(gap.max() * 1000), "ibs_sample_spacing_mm": result.spacing * 1000}


def run_geometry_benchmark(quick: bool = False, seed: int = 0) -> dict:
    """All geometry figures as one flat dict."""
    rng = np.random.default_rng(seed)
    mug = generate("mug", 3)
    repeats = 2 if quick else 3
    out = {"cpu_count": os.cpu_count(), "quick": quick, "seed": seed}
    out.update(ray_benchmark(mug, 2000 if quick else 10_000, repeats, rng))
    out.update(scf_accuracy(mug, 100 if quick else 1000, rng))
    out.update(ibs_benchmark(repeats))
    return out
