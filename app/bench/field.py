"""`nift bench-field`: data generation rate, training throughput and the imitation inner loop's cost."""
from __future__ import annotations

import tempfile
import time

import numpy as np
import torch
from tqdm import tqdm

from app.nift.field import FieldConfig, NeuralField, load_field
from app.training.data import DataConfig, make_dataset
from app.training.dataset import FieldData
from app.training.train import TrainConfig, run_epoch


def data_rate(instances: int, views: int, workers: int, seed: int) -> tuple[float, str]:
    """Samples per second of `nift make-data` at the default settings, and the data directory."""
    out = tempfile.mkdtemp(prefix="nift-bench-data-")
    cfg = DataConfig(instances=instances, views=views, shard_instances=max(1, instances * 3 // workers), seed=seed)
    report = make_dataset(cfg, out, workers=workers, progress=False)
    return report.new_samples / report.seconds, out


def train_rate(data: FieldData, field_cfg: FieldConfig, steps: int, batch_size: int = 16) -> float:
    """Training samples per second (forward, backward, Adam step) of `nift train`'s own epoch loop."""
    cfg = TrainConfig(field=field_cfg, batch_size=batch_size)
    model = NeuralField(field_cfg)
    opt = torch.optim.Adam(model.parameters(), lr=cfg.lr)
    rng = np.random.default_rng(0)
    idx = rng.choice(data.n_samples, (steps + 1) * batch_size)
    quiet = tqdm(disable=True)
    run_epoch(model, opt, data, idx[:batch_size], cfg, rng, None, quiet)  # warm-up step
    start = time.perf_counter()
    run_epoch(model, opt, data, idx[batch_size:], cfg, rng, None, quiet)
    return steps * batch_size / (time.perf_counter() - start)


def feature_time(field: NeuralField, cloud: np.ndarray, repeats: int, inits: int = 10, points: int = 500) -> float:
    """Seconds for features + backward w.r.t. the points of an (inits x points) batch: one imitation step."""
    with torch.no_grad():
        latent = field.encode(cloud)
    x = torch.randn(inits, points, 3) * 0.05 + latent.center / field.config.input_scale
    x.requires_grad_(True)
    times = []
    for _ in range(repeats + 1):
        start = time.perf_counter()
        field.features(latent, x).abs().sum().backward()
        times.append(time.perf_counter() - start)
    return float(np.median(times[1:]))


def run_field_benchmark(quick: bool = False, seed: int = 0, workers: int = 2) -> dict:
    """All figures of bench-field."""
    rate, out = data_rate(2 if quick else 10, 8, workers, seed)
    data = FieldData(out)
    field = load_field("nif")
    t = feature_time(field, data.cloud[0], repeats=5 if quick else 30)
    return {
        "data_samples_per_s": round(rate, 2),
        "train_samples_per_s": round(train_rate(data, field.config, steps=3 if quick else 20), 1),
        "feature_batch": "10 x 500 points",
        "feature_ms_fwd_bwd": round(1000 * t, 2),
        "feature_points_per_s": round(5000 / t),
        "imitation_500_iterations_s": round(500 * t, 2),
        "feature_dim": field.config.feature_dim,
        "threads": torch.get_num_threads(),
    }
