"""`nift make-data`: field training data - clouds as the camera sees them, query points, SCF and occupancy.

Per object instance (category, seed from the chosen split):
- Q query points in the instance's canonical frame at unit scale: a share uniform in a box
  `box_factor` x its bounding box (about the box centre, as the paper says), the rest near the
  surface (surface samples + Gaussian noise); their SCF (bands 0..scf_order) and occupancy.
- `views` samples, each a uniform random scale s, a Haar-random rotation R and a camera view:
  the cloud, rotated into the world frame (object origin at the world origin).

A sample's query points are x = R (s q). Reusing one instance's labels for all its samples is
exact, not an approximation: SCF is invariant to scale and translation exactly and to rotation
up to its 1 % quadrature error (`app/nift/scf.py`), and occupancy is invariant to all three. It
makes data 5-10x cheaper, which matters on 2 cores. Store SCF up to order 10 once; a field of
order n trains on bands 0..n (the band powers do not depend on the highest order computed).

Files: `DIR/manifest.json` (format nift-data/1: the config, the shards done, sizes, rates) and
`DIR/shard-NNNNN.npz`, each written atomically; an interrupted run resumes where it stopped, and
the same seed gives the same files. Shards are made as Ray tasks (app.fanout) and written here by
the command, so workers on other machines need no shared disk.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Iterator

import numpy as np
from tqdm import tqdm

from app.fanout.cluster import ClusterConfig
from app.fanout.run import fan_out
from app.io_utils import write_json, write_npz
from app.nift.raycast import scene_of
from app.nift.scf import compute_scf
from app.objects import IN_DOMAIN, check_category, generate, split
from app.objects.families import family_of
from app.training.manifest import FORMAT, read_manifest
from app.training.views import CAMERAS, observe
from hardware.se3 import random_rotations


@dataclass(frozen=True)
class DataConfig:
    """What to generate; stored in the manifest so a resumed run must match it."""

    split: str = "train"
    categories: tuple[str, ...] = IN_DOMAIN
    instances: int = 500  # per category
    views: int = 8  # samples (scale, rotation, camera view) per instance
    camera: str = "single"  # "single" (our cell) or "fused" (four corner cameras, the paper's)
    points: int = 1024  # cloud size (farthest point sampling, as perception does)
    queries: int = 2000  # labelled query points per instance
    near_surface: float = 0.4  # share of queries near the surface
    surface_sigma: float = 0.01  # metres, spread of near-surface queries (unit-scale object)
    box_factor: float = 1.5
    scale: tuple[float, float] = (0.8, 1.2)
    scf_order: int = 10
    shard_instances: int = 50
    seed: int = 0

    def __post_init__(self) -> None:
        for c in self.categories:
            check_category(c)
        if self.camera not in CAMERAS:
            raise ValueError(f"unknown camera setting {self.camera!r}; choose one of {', '.join(CAMERAS)}")
        for name in ("instances", "views", "queries", "points"):
            if getattr(self, name) < 1:
                raise ValueError(f"--{name} must be >= 1, got {getattr(self, name)}")
        if not 0.0 <= self.near_surface <= 1.0:
            raise ValueError(f"near_surface is a share in [0, 1], got {self.near_surface}")
        available = len(split(self.categories[0], self.split))
        if self.instances > available:
            raise ValueError(f"the {self.split} split has {available} instances per category, asked for {self.instances}")


def plan(cfg: DataConfig) -> list[list[tuple[str, int]]]:
    """The (category, seed) instances of every shard, deterministic in cfg.seed."""
    rng = np.random.default_rng(cfg.seed)
    items = []
    for category in cfg.categories:
        seeds = rng.choice(split(category, cfg.split), size=cfg.instances, replace=False)
        items += [(category, int(s)) for s in seeds]
    order = rng.permutation(len(items))
    items = [items[i] for i in order]
    return [items[i:i + cfg.shard_instances] for i in range(0, len(items), cfg.shard_instances)]


def query_points(mesh, cfg: DataConfig, rng: np.random.Generator) -> np.ndarray:
    """(Q, 3) canonical-frame queries: uniform in the enlarged box, plus near the surface."""
    lo, hi = mesh.bounds
    center, half = (lo + hi) / 2, (hi - lo) / 2 * cfg.box_factor
    n_near = int(round(cfg.queries * cfg.near_surface))
    box = rng.uniform(center - half, center + half, size=(cfg.queries - n_near, 3))
    surface = mesh.sample(n_near, seed=int(rng.integers(2**31))) if n_near else np.zeros((0, 3))
    near = surface + rng.normal(scale=cfg.surface_sigma, size=surface.shape)
    # stored as float16 (steps of 0.06 mm at 0.1 m): round first, so labels belong to the stored points
    return np.concatenate([box, near]).astype(np.float16).astype(np.float32)


def make_instance(category: str, seed: int, cfg: DataConfig, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Labels of one instance and its `views` samples."""
    mesh = generate(category, seed)
    scene = scene_of(mesh)
    q = query_points(mesh, cfg, rng)
    scf = compute_scf(scene, q, order=cfg.scf_order)
    occ = scene.compute_occupancy(q.astype(np.float32)).numpy() > 0.5
    center = mesh.bounds.mean(axis=0)
    radius = float(np.linalg.norm(mesh.vertices - center, axis=1).max())
    rotations = random_rotations(cfg.views, rng)
    scales = rng.uniform(*cfg.scale, size=cfg.views)
    clouds = []
    for R, s in zip(rotations, scales):
        scaled = scene_of(mesh.copy().apply_scale(s))
        cloud = observe(scaled, cfg.camera, R, s * center, s * radius, cfg.points, rng)
        clouds.append(cloud @ R.T)
    return {"queries": q.astype(np.float16), "scf": scf.astype(np.float16), "occ": occ,
            "rotation": rotations.astype(np.float32), "scale": scales.astype(np.float32),
            "cloud": np.stack(clouds).astype(np.float16)}


def shard_name(index: int) -> str:
    return f"shard-{index:05d}.npz"


def shard_arrays(cfg: DataConfig, index: int, instances: list[tuple[str, int]]) -> dict[str, np.ndarray]:
    """One shard's arrays (a function of the config and the shard's index alone)."""
    rng = np.random.default_rng(np.random.SeedSequence([cfg.seed, index]))
    parts = [make_instance(c, s, cfg, rng) for c, s in instances]
    arrays = {
        "category": np.array([cfg.categories.index(c) for c, _ in instances], dtype=np.int8),
        "seed": np.array([s for _, s in instances], dtype=np.int64),
        "queries": np.stack([p["queries"] for p in parts]),  # (I, Q, 3)
        "scf": np.stack([p["scf"] for p in parts]),  # (I, Q, order + 1)
        "occ": np.stack([p["occ"] for p in parts]),  # (I, Q)
        "sample_instance": np.repeat(np.arange(len(parts), dtype=np.int32), cfg.views),  # (S,)
        "rotation": np.concatenate([p["rotation"] for p in parts]),  # (S, 3, 3)
        "scale": np.concatenate([p["scale"] for p in parts]),  # (S,)
        "cloud": np.concatenate([p["cloud"] for p in parts]),  # (S, N, 3)
    }
    return arrays


def write_shard(cfg: DataConfig, index: int, instances: list[tuple[str, int]], arrays: dict[str, np.ndarray],
                out: Path, seconds: float) -> dict:
    """Atomically write one shard; return its manifest record."""
    path = write_npz(out / shard_name(index), arrays)
    return {"file": path.name, "instances": len(instances), "samples": len(instances) * cfg.views,
            "families": sorted({f"{c}/{family_of(c, s)}" for c, s in instances}),
            "bytes": path.stat().st_size, "seconds": round(seconds, 3)}


def _timed_shard(cfg: DataConfig, job: tuple[int, list[tuple[str, int]]]) -> tuple[dict[str, np.ndarray], float]:
    """A worker's task: one shard's arrays and the seconds they took."""
    start = time.perf_counter()
    return shard_arrays(cfg, *job), time.perf_counter() - start


def _same(cfg: DataConfig) -> DataConfig:
    return cfg


def config_to_json(cfg: DataConfig) -> dict:
    d = asdict(cfg)
    d["categories"], d["scale"] = list(cfg.categories), list(cfg.scale)
    return d


@dataclass
class DataReport:
    """What a make-data run did: totals and rates for the run itself."""

    manifest: dict
    new_samples: int = 0
    seconds: float = 0.0
    failed: dict[int, str] = field(default_factory=dict)  # shard index -> the error its task raised

    def figures(self) -> dict:
        total = self.manifest["shards"]
        failed = {"failed_shards": {str(i): e for i, e in sorted(self.failed.items())}} if self.failed else {}
        return failed | {
            "out": self.manifest["out"],
            "samples": sum(s["samples"] for s in total),
            "instances": sum(s["instances"] for s in total),
            "new_samples": self.new_samples,
            "seconds": round(self.seconds, 1),
            "samples_per_s": round(self.new_samples / self.seconds, 2) if self.seconds > 0 else None,
            "megabytes": round(sum(s["bytes"] for s in total) / 1e6, 1),
            "complete": self.manifest["complete"],
        }


def run_shards(cfg: DataConfig, shards: list, todo: list[int], out: Path,
               cluster: ClusterConfig) -> Iterator[dict | tuple[int, str]]:
    """Yield, as shards finish (app.fanout), a written shard's record, or (index, error) for a shard whose
    task raised: nothing of it is written, and running again retries it."""
    jobs = [(i, shards[i]) for i in todo]
    for outcome in fan_out(_timed_shard, jobs, _same, cfg, cluster, helps=True):  # a shard's state: none
        index, instances = jobs[outcome.index]
        if outcome.failed:
            yield index, outcome.error
            continue
        arrays, seconds = outcome.value
        yield write_shard(cfg, index, instances, arrays, out, seconds)


def make_dataset(cfg: DataConfig, out: str | Path, workers: int | ClusterConfig = 2, progress: bool = True) -> DataReport:
    """Generate (or resume) a dataset in `out`; `workers`: local processes, or where to run (app.fanout)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    manifest = read_manifest(out)
    if manifest is not None and manifest["config"] != config_to_json(cfg):
        diff = [k for k, v in config_to_json(cfg).items() if manifest["config"].get(k) != v]
        raise ValueError(f"{out} holds data made with a different config ({', '.join(diff)}); use another --out")
    manifest = manifest or {"format": FORMAT, "config": config_to_json(cfg), "shards": [], "complete": False}
    manifest["out"] = str(out)
    shards = plan(cfg)
    done = {s["file"] for s in manifest["shards"] if (out / s["file"]).is_file()}
    manifest["shards"] = [s for s in manifest["shards"] if s["file"] in done]
    todo = [i for i in range(len(shards)) if shard_name(i) not in done]
    manifest["complete"] = not todo  # until the last shard is written, the set is marked incomplete
    start, report = time.perf_counter(), DataReport(manifest)
    bar = tqdm(total=sum(len(s) for s in shards), initial=sum(s["instances"] for s in manifest["shards"]),
               unit="inst", disable=not progress, desc="make-data")
    cluster = workers if isinstance(workers, ClusterConfig) else ClusterConfig(workers)
    for record in run_shards(cfg, shards, todo, out, cluster):
        if isinstance(record, tuple):
            report.failed[record[0]] = record[1]
            continue
        manifest["shards"].append(record)
        manifest["shards"].sort(key=lambda s: s["file"])
        report.new_samples += record["samples"]
        write_json(out / "manifest.json", manifest)  # after every shard: resumable
        bar.update(record["instances"])
    bar.close()
    manifest["complete"] = len(manifest["shards"]) == len(shards)
    write_json(out / "manifest.json", manifest)
    report.seconds = time.perf_counter() - start
    return report
