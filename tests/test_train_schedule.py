"""Training options: the cosine learning-rate schedule and starting from saved weights (--init)."""
import dataclasses

import numpy as np
import pytest
import torch

from app.nift.field import FieldConfig, NeuralField, save_field
from app.training.train import TrainConfig, init_from, lr_at

SMALL = FieldConfig(latent=8, encoder_width=8, encoder_blocks=1, decoder_width=16, decoder_blocks=1)


def test_cosine_schedule_hits_its_ends_and_midpoint():
    cfg = TrainConfig(lr=1e-3, lr_final=1e-5, epochs=10)
    assert lr_at(cfg, 0, 0) == pytest.approx(1e-3)
    assert lr_at(cfg, 5, 0) == pytest.approx((1e-3 + 1e-5) / 2)
    assert lr_at(cfg, 10, 0) == pytest.approx(1e-5)
    assert lr_at(cfg, 12, 0) == pytest.approx(1e-5)  # past the budget: stays at the floor


def test_schedule_follows_the_wall_clock_budget_when_it_ends_first():
    cfg = TrainConfig(lr=1e-3, lr_final=0.0, epochs=100, minutes=10)
    assert lr_at(cfg, 1, 300) == pytest.approx(5e-4)  # half the minutes, 1 % of the epochs
    assert lr_at(dataclasses.replace(cfg, lr_final=None), 1, 300) == 1e-3  # no schedule: constant


def test_init_from_another_order_keeps_the_trunk_and_starts_a_fresh_head(tmp_path):
    torch.manual_seed(0)
    source = NeuralField(SMALL)
    path = save_field(source, tmp_path / "order5.pt")
    torch.manual_seed(1)
    target = NeuralField(dataclasses.replace(SMALL, scf_order=3))
    head_before = {k: v.clone() for k, v in target.state_dict().items()}
    fresh = init_from(target, path)
    assert fresh and all(target.state_dict()[k].shape != source.state_dict()[k].shape for k in fresh)
    cloud = np.random.default_rng(0).normal(scale=0.05, size=(64, 3))
    x = torch.tensor(np.random.default_rng(1).normal(scale=0.05, size=(1, 20, 3)), dtype=torch.float32)
    with torch.no_grad():  # same trunk -> same features; the head is the new one, untouched
        assert torch.equal(source.eval().features(source.encode(cloud), x),
                           target.eval().features(target.encode(cloud), x))
    for k in fresh:
        assert torch.equal(target.state_dict()[k], head_before[k])
