"""A `nift make-data` directory in memory, and random training batches drawn from it.

A batch is built in numpy, vectorised over the batch (a per-item DataLoader was the bottleneck
for a model this small): for each sample, a random subset of its cloud and of its instance's
labelled query points, moved into the sample's pose, x = R (s q).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from app.io_utils import NPY_ERRORS
from app.training.manifest import read_manifest, shard_path

ARRAYS = ("category", "seed", "queries", "scf", "occ", "sample_instance", "rotation", "scale", "cloud")


class FieldData:
    """All shards of one data directory: instance labels and per-sample clouds and poses."""

    def __init__(self, path: str | Path) -> None:
        path = Path(path)
        manifest = read_manifest(path)
        if manifest is None:
            raise FileNotFoundError(f"no manifest.json in {path}: make the data first with `nift make-data --out {path}`")
        if not manifest["shards"]:
            raise ValueError(f"{path} holds no shards yet")
        if not manifest.get("complete", True):  # manifests before the flag existed were written complete only
            raise ValueError(f"{path} is incomplete ({len(manifest['shards'])} shards: `nift make-data` was stopped "
                             f"before the end); resume it with the same `nift make-data --out {path} ...`")
        self.path, self.manifest, self.config = path, manifest, manifest["config"]
        parts: dict[str, list[np.ndarray]] = {k: [] for k in ARRAYS}
        offset = 0
        for shard in manifest["shards"]:
            file = shard_path(path, shard.get("file") if isinstance(shard, dict) else shard)
            try:
                with np.load(file, allow_pickle=False) as z:
                    for k in ARRAYS:
                        parts[k].append(z[k] + offset if k == "sample_instance" else z[k])
                    offset += len(z["seed"])
            except NPY_ERRORS as exc:  # truncated, foreign, pickled
                raise ValueError(f"{file} is not a readable shard ({type(exc).__name__}: {exc})") from None
        for k, v in parts.items():
            setattr(self, k, np.concatenate(v))
        self.cloud = self.cloud.astype(np.float32)
        self.queries = self.queries.astype(np.float32)  # float16 on disk since data made after 2026-11-26

    @property
    def n_samples(self) -> int:
        return len(self.sample_instance)

    @property
    def scf_order(self) -> int:
        return self.scf.shape[-1] - 1

    def split(self, fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
        """Sample indices (train, validation), split by instance so no object is in both."""
        rng = np.random.default_rng(seed)
        instances = rng.permutation(len(self.seed))
        n_val = max(1, int(round(fraction * len(instances)))) if fraction > 0 else 0
        held = np.isin(self.sample_instance, instances[:n_val])
        return np.flatnonzero(~held), np.flatnonzero(held)

    def batch(self, idx: np.ndarray, cloud_points: int, query_points: int, order: int,
              rng: np.random.Generator) -> dict[str, torch.Tensor]:
        """Tensors for samples idx: cloud (B, n, 3), points (B, T, 3), scf (B, T, order+1), occ (B, T)."""
        if order > self.scf_order:
            raise ValueError(f"the data holds SCF up to order {self.scf_order}, asked for {order}")
        B = len(idx)
        clouds = self.cloud[idx]  # (B, N, 3)
        n = min(cloud_points, clouds.shape[1])
        pick = np.argsort(rng.random((B, clouds.shape[1])), axis=1)[:, :n]
        cloud = np.take_along_axis(clouds, pick[..., None], axis=1)  # (B, n, 3)
        inst = self.sample_instance[idx]
        qi = rng.integers(0, self.queries.shape[1], size=(B, query_points))
        q = self.queries[inst[:, None], qi]  # (B, T, 3) canonical, unit scale
        points = np.einsum("bij,btj->bti", self.rotation[idx], q * self.scale[idx, None, None])
        return {
            "cloud": torch.from_numpy(cloud),
            "points": torch.from_numpy(points.astype(np.float32)),
            "scf": torch.from_numpy(self.scf[inst[:, None], qi, :order + 1].astype(np.float32)),
            "occ": torch.from_numpy(self.occ[inst[:, None], qi].astype(np.float32)),
        }
