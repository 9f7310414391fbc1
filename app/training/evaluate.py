"""Field metrics: SCF R^2 per band (mean = the paper's "mean R^2") and occupancy accuracy."""
from __future__ import annotations

import numpy as np
import torch

from app.nift.field import NeuralField
from app.training.dataset import FieldData


def r2_per_band(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """Coefficient of determination per column of (M, K) arrays: 1 - SS_res / SS_tot."""
    ss_res = np.sum((pred - true) ** 2, axis=0)
    ss_tot = np.sum((true - true.mean(axis=0)) ** 2, axis=0)
    return 1.0 - ss_res / np.maximum(ss_tot, 1e-12)


def loss_of(field: NeuralField, batch: dict[str, torch.Tensor]) -> torch.Tensor:
    """L1 on standardised SCF (NIF) or binary cross entropy on occupancy logits (NDF), mean over points."""
    return loss_from_head(field, field.head(field.encode(batch["cloud"]), batch["points"]), batch)


def loss_from_head(field: NeuralField, out: torch.Tensor, batch: dict[str, torch.Tensor]) -> torch.Tensor:
    """The loss of a head output (B, T, out_dim) against the batch's labels."""
    if field.config.target == "scf":
        return torch.nn.functional.l1_loss(out, field.standardise(batch["scf"]))
    return torch.nn.functional.binary_cross_entropy_with_logits(out[..., 0], batch["occ"])


@torch.no_grad()
def evaluate(field: NeuralField, data: FieldData, idx: np.ndarray, cloud_points: int, query_points: int,
             seed: int = 0, batch_size: int = 16) -> dict:
    """Loss and metrics over samples idx (fixed random draws, so repeated calls compare)."""
    field.eval()
    rng = np.random.default_rng(seed)
    order = field.config.scf_order
    losses, preds, trues = [], [], []
    for start in range(0, len(idx), batch_size):
        batch = data.batch(idx[start:start + batch_size], cloud_points, query_points, order, rng)
        batch = {k: v.to(field.device) for k, v in batch.items()}
        out = field.head(field.encode(batch["cloud"]), batch["points"])  # one forward pass for both
        losses.append(float(loss_from_head(field, out, batch)) * len(batch["cloud"]))
        pred = field.from_head(out)
        key = "scf" if field.config.target == "scf" else "occ"
        preds.append(pred.reshape(-1, pred.shape[-1] if key == "scf" else 1).cpu().numpy())
        trues.append(batch[key].reshape(preds[-1].shape).cpu().numpy())
    pred, true = np.concatenate(preds), np.concatenate(trues)
    out = {"loss": sum(losses) / len(idx), "samples": int(len(idx))}
    if field.config.target == "scf":
        r2 = r2_per_band(pred, true)
        out.update(scf_r2=float(r2.mean()), scf_r2_per_band=[round(float(v), 4) for v in r2])
    else:
        out.update(occ_accuracy=float(np.mean((pred > 0.5) == (true > 0.5))), occupied_share=float(true.mean()))
    return out
