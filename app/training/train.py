"""`nift train`: fit a field (NIF on SCF, NDF on occupancy) with checkpoints, resume and a model card.

Adam (lr 1e-4 as in the paper by default), L1 for SCF, BCE for occupancy, 10 % of the training
instances held out for validation. Each epoch ends with a checkpoint (`OUT/last.pt`: model,
optimiser, RNG, history) and, when the validation loss improved, `OUT/best.pt`; `--resume`
continues from `last.pt`. A wall-clock budget (`minutes`) ends training early at a step
boundary, checkpointed, so a session's worth of CPU can be spent exactly. At the end the best
weights are evaluated on held-out test-split data and written with their model card.

`lr_final` adds a cosine decay of the step size over the run's budget (progress p in [0, 1]: the
larger of the share of epochs and, with a budget, the share of minutes spent):

    lr(p) = lr_final + (lr - lr_final) (1 + cos(pi p)) / 2

`init` starts from existing weights (fine-tuning, or a longer run from the shipped field): every
tensor whose name and shape match is copied - so a NIF of another SCF order keeps the encoder
and decoder and gets a fresh head.
"""
from __future__ import annotations

import pickle
import platform
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from app.io_utils import atomic_path
from app.nift.field import FieldConfig, NeuralField, load_field, save_field
from app.nift.schedule import cosine
from app.training.dataset import FieldData
from app.training.evaluate import evaluate, loss_of

PAPER = {"scf": {"scf_r2": 0.86}, "occ": {"occ_accuracy": 0.92}}  # paper Sec. IV-A, ShapeNet


@dataclass(frozen=True)
class TrainConfig:
    """Optimisation settings; the architecture is `field`."""

    field: FieldConfig = field(default_factory=FieldConfig)
    epochs: int = 10
    batch_size: int = 16
    lr: float = 1e-4
    query_points: int = 500
    val_fraction: float = 0.1
    val_samples: int = 256  # validation after each epoch uses this fixed subset (full set: 10x the time)
    minutes: float | None = None  # wall-clock budget; None = run all epochs
    lr_final: float | None = None  # cosine decay of lr to this over the budget; None = constant lr
    seed: int = 0


def lr_at(cfg: TrainConfig, epoch: float, seconds: float) -> float:
    """The step size at a point of the run (epoch: passes done; seconds: wall time spent)."""
    if cfg.lr_final is None:
        return cfg.lr
    progress = epoch / cfg.epochs
    if cfg.minutes:
        progress = max(progress, seconds / (60 * cfg.minutes))
    return cosine(cfg.lr, cfg.lr_final, progress)


def init_from(model: NeuralField, path: str | Path) -> list[str]:
    """Copy every tensor of a saved field whose name and shape match; return the names left fresh."""
    source = load_field(path).state_dict()
    own = model.state_dict()
    fresh = [k for k, v in own.items() if k not in source or source[k].shape != v.shape]
    model.load_state_dict({k: source[k] if k not in fresh else v for k, v in own.items()})
    return fresh


def pick_device() -> torch.device:
    """CUDA when present, else CPU."""
    return torch.device("cuda" if torch.cuda.is_available() else "cpu")


def save_checkpoint(path: Path, model: NeuralField, opt: torch.optim.Optimizer, state: dict) -> None:
    """Atomically write everything needed to resume."""
    with atomic_path(path) as tmp:
        torch.save({"config": asdict(model.config), "model": model.state_dict(), "optimizer": opt.state_dict(),
                    "state": state}, tmp)


def load_checkpoint(path: Path, model: NeuralField, opt: torch.optim.Optimizer) -> dict:
    """Restore model and optimiser from a checkpoint; return the saved loop state."""
    if not path.is_file():
        raise FileNotFoundError(f"no checkpoint to resume at {path}")
    try:  # tensors and plain values only: a checkpoint never runs code when it is read
        blob = torch.load(path, map_location=model.device, weights_only=True)
    except (pickle.UnpicklingError, RuntimeError, EOFError) as exc:
        reason = (str(exc).strip().splitlines() or [type(exc).__name__])[0][:120]
        raise ValueError(f"{path}: not a checkpoint that loads safely ({reason})") from None
    if asdict(FieldConfig(**blob["config"])) != asdict(model.config):  # keys added since take their defaults
        raise ValueError(f"{path} was trained with a different architecture; start a new --out")
    model.load_state_dict(blob["model"])
    opt.load_state_dict(blob["optimizer"])
    return blob["state"]


def run_epoch(model, opt, data: FieldData, idx: np.ndarray, cfg: TrainConfig, rng: np.random.Generator,
              state: dict, deadline: float | None, bar: tqdm) -> tuple[float, int, bool]:
    """One pass over idx in random batches: (mean loss, steps, finished). The deadline or Ctrl-C
    ends it early at a step boundary (finished = False); the caller then checkpoints and evaluates."""
    model.train()
    order = rng.permutation(idx)
    total, steps = 0.0, 0
    begun = time.monotonic()
    try:
        for start in range(0, len(order) - cfg.batch_size + 1, cfg.batch_size):
            if deadline is not None and time.monotonic() > deadline:
                return total / max(steps, 1), steps, False
            lr = lr_at(cfg, state["epoch"] + start / len(order), state["seconds"] + time.monotonic() - begun)
            for group in opt.param_groups:
                group["lr"] = lr
            batch = data.batch(order[start:start + cfg.batch_size], cfg.field.cloud_points, cfg.query_points,
                               cfg.field.scf_order, rng)
            batch = {k: v.to(model.device) for k, v in batch.items()}
            loss = loss_of(model, batch)
            opt.zero_grad()
            loss.backward()
            opt.step()
            total, steps = total + loss.item(), steps + 1
            bar.update(cfg.batch_size)
            bar.set_postfix(loss=f"{total / steps:.4f}")
    except KeyboardInterrupt:
        return total / max(steps, 1), steps, False
    return total / max(steps, 1), steps, True


def train(cfg: TrainConfig, data_dir: str | Path, out: str | Path, eval_dir: str | Path | None = None,
          weights: str | Path | None = None, resume: bool = False, progress: bool = True, command: str = "",
          init: str | Path | None = None) -> dict:
    """Train, checkpoint, evaluate and write the final weights + model card; return the card."""
    out = Path(out)
    data = FieldData(data_dir)  # before the run directory exists: bad data leaves nothing behind
    out.mkdir(parents=True, exist_ok=True)
    torch.manual_seed(cfg.seed)
    device = pick_device()
    train_idx, val_idx = data.split(cfg.val_fraction, cfg.seed)
    val_idx = np.random.default_rng(cfg.seed).permutation(val_idx)[:cfg.val_samples]
    model = NeuralField(cfg.field).to(device)
    fresh = init_from(model, init) if init is not None and not resume else []
    if cfg.field.target == "scf":
        bands = data.scf[np.unique(data.sample_instance[train_idx]), :, :cfg.field.out_dim].astype(np.float64)
        model.set_target_stats(bands.mean(axis=(0, 1)), bands.std(axis=(0, 1)))
    opt = torch.optim.Adam(model.parameters(), lr=cfg.lr)
    state = {"epoch": 0, "steps": 0, "seconds": 0.0, "best_val": float("inf"), "history": [],
             "rng": np.random.default_rng(cfg.seed).bit_generator.state,
             "init": None if init is None else {"weights": str(init), "fresh": fresh}}
    if resume:
        state = load_checkpoint(out / "last.pt", model, opt)
    rng = np.random.default_rng()
    rng.bit_generator.state = state["rng"]
    start = time.monotonic()
    deadline = None if cfg.minutes is None else start + 60 * cfg.minutes - state["seconds"]
    bar = tqdm(total=cfg.epochs * len(train_idx), initial=state["epoch"] * len(train_idx), unit="sample",
               disable=not progress, desc=f"train {cfg.field.target}")
    finished = True
    while state["epoch"] < cfg.epochs and finished:
        loss, steps, finished = run_epoch(model, opt, data, train_idx, cfg, rng, state, deadline, bar)
        val = evaluate(model, data, val_idx, data.cloud.shape[1], cfg.query_points) if len(val_idx) else {"loss": loss}
        state["epoch"] += 1 if finished else steps * cfg.batch_size / len(train_idx)
        state["steps"] += steps
        state["seconds"] += time.monotonic() - start
        start = time.monotonic()
        state["history"].append({"epoch": round(state["epoch"], 3), "train_loss": loss, **val})
        state["rng"] = rng.bit_generator.state
        if val["loss"] < state["best_val"]:
            state["best_val"] = val["loss"]
            save_field(model, out / "best.pt")
        save_checkpoint(out / "last.pt", model, opt, state)
    bar.close()
    best = load_field(out / "best.pt", device)
    card = model_card(cfg, data, state, device, command, sum(p.numel() for p in best.parameters()))
    if eval_dir is not None:
        test = FieldData(eval_dir)
        card["test"] = {"data": str(eval_dir), "split": test.config["split"],
                        **evaluate(best, test, np.arange(test.n_samples), test.cloud.shape[1], cfg.query_points)}
    save_field(best, weights or out / "field.pt", card)
    return card


def model_card(cfg: TrainConfig, data: FieldData, state: dict, device: torch.device, command: str,
               n_params: int) -> dict:
    """What a user needs to trust (or reproduce) a weights file."""
    best = min(state["history"], key=lambda h: h["loss"])
    return {
        "format": "nift-field-card/1",
        "name": "NIF" if cfg.field.target == "scf" else "NDF",
        "target": cfg.field.target,
        "architecture": {**asdict(cfg.field), "feature_dim": cfg.field.feature_dim, "parameters": n_params},
        "data": {"dir": str(data.path), "samples": data.n_samples, "instances": len(data.seed),
                 "config": data.config},
        "training": {"epochs": round(state["epoch"], 3), "steps": state["steps"], "batch_size": cfg.batch_size,
                     "lr": cfg.lr, "lr_final": cfg.lr_final, "init": state.get("init"),
                     "cloud_points": cfg.field.cloud_points, "query_points": cfg.query_points,
                     "val_fraction": cfg.val_fraction, "seed": cfg.seed, "minutes_budget": cfg.minutes,
                     "seconds": round(state["seconds"], 1), "device": device_name(device),
                     "torch": torch.__version__, "threads": torch.get_num_threads()},
        "validation": best,
        "history": state["history"],
        "paper": PAPER[cfg.field.target],
        "command": command,
    }


def device_name(device: torch.device) -> str:
    if device.type == "cuda":
        return torch.cuda.get_device_name(device)
    return f"cpu ({platform.processor() or platform.machine()}, {torch.get_num_threads()} threads)"
