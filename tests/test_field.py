"""The neural field: equivariance, gradients, save/load, shipped weights' accuracy on unseen objects."""
from dataclasses import asdict

import numpy as np
import pytest
import torch

from app.nift.field import WEIGHTS_DIR, FieldConfig, NeuralField, field_path, load_field, read_card, save_field
from app.training.data import DataConfig, make_dataset
from app.training.dataset import FieldData
from app.training.evaluate import evaluate, loss_of
from hardware.se3 import random_rotations

SMALL = FieldConfig(latent=8, encoder_width=8, encoder_blocks=2, decoder_width=16, decoder_blocks=2)


@pytest.fixture(scope="module")
def test_split_data(tmp_path_factory):
    """Unseen test-split instances, two single-view samples each, as the shipped fields were evaluated."""
    out = tmp_path_factory.mktemp("test-data")
    make_dataset(DataConfig(split="test", instances=4, views=2, shard_instances=4, seed=7), out, workers=1,
                 progress=False)
    return FieldData(out)


@pytest.mark.parametrize("field", [NeuralField(FieldConfig()), NeuralField(SMALL), "nif", "ndf"],
                         ids=["default-init", "small-init", "shipped-nif", "shipped-ndf"])
def test_features_are_se3_invariant(field):
    """f(R x + t | R O + t) = f(x | O): the field moves with the object."""
    field = load_field(field) if isinstance(field, str) else field.eval()
    rng = np.random.default_rng(3)
    cloud = rng.normal(scale=0.05, size=(800, 3))  # more than cloud_points: the subset must move along
    x = rng.normal(scale=0.08, size=(2, 50, 3))
    with torch.no_grad():
        f0 = field.features(field.encode(cloud), x)
        for R in random_rotations(3, rng):
            t = rng.uniform(-0.5, 0.5, 3)
            f1 = field.features(field.encode(cloud @ R.T + t), x @ R.T + t)
            assert float((f1 - f0).norm() / f0.norm()) < 1e-4
    assert f0.shape == (2, 50, field.config.feature_dim)


def test_features_match_finite_differences():
    """Autograd d features / d points agrees with central differences (float64)."""
    field = NeuralField(SMALL).double().eval()
    rng = np.random.default_rng(0)
    latent = field.encode(rng.normal(scale=0.05, size=(64, 3)))
    x = torch.tensor(rng.normal(scale=0.05, size=(1, 4, 3)), requires_grad=True)
    assert torch.autograd.gradcheck(lambda p: field.features(latent, p), (x,), eps=1e-6, atol=1e-5)


def test_a_few_steps_lower_the_loss_and_reload_gives_identical_outputs(test_split_data, tmp_path):
    torch.manual_seed(0)
    field = NeuralField(SMALL)
    batch = test_split_data.batch(np.arange(4), 128, 128, SMALL.scf_order, np.random.default_rng(0))
    opt = torch.optim.Adam(field.parameters(), lr=3e-3)
    first = loss_of(field, batch).item()
    for _ in range(40):
        loss = loss_of(field, batch)
        opt.zero_grad()
        loss.backward()
        opt.step()
    assert loss_of(field, batch).item() < 0.8 * first
    path = save_field(field, tmp_path / "f.pt", card={"note": "test"})
    again = load_field(path)
    with torch.no_grad():
        z0, z1 = field.eval().encode(batch["cloud"]), again.encode(batch["cloud"])
        assert torch.equal(field.features(z0, batch["points"]), again.features(z1, batch["points"]))
    assert (tmp_path / "f.json").is_file()


def test_bad_weight_files_are_refused_with_clear_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="no field weights"):
        load_field(tmp_path / "missing.pt")
    garbage = tmp_path / "garbage.pt"
    garbage.write_bytes(b"not a torch file")
    with pytest.raises(ValueError, match="not a readable field weights file"):
        load_field(garbage)
    foreign = tmp_path / "foreign.pt"
    torch.save({"format": "something-else/3"}, foreign)
    with pytest.raises(ValueError, match="expected format 'nift-field/1'"):
        load_field(foreign)
    good = save_field(NeuralField(SMALL), tmp_path / "good.pt")
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(good.read_bytes()[:200])
    with pytest.raises(ValueError, match="not a readable"):
        load_field(truncated)
    with pytest.raises(ValueError, match="unknown field target"):
        FieldConfig(target="sdf")


def test_shipped_weights_carry_model_cards():
    for name, target in (("nif", "scf"), ("ndf", "occ")):
        card = read_card(name)
        assert card["target"] == target == load_field(name).config.target
        assert card["training"]["seconds"] > 0 and card["data"]["samples"] > 0
        assert field_path(name).stat().st_size < 10e6


def test_every_shipped_weights_file_matches_its_card():
    """Fused, gpu2 and Table III's per-order NIFs too: the card's target and SCF order are the net's."""
    paths = sorted(WEIGHTS_DIR.rglob("*.pt"))
    assert {p.parent.name for p in paths} >= {"weights", "fused", "gpu2", "table3"}
    for path in paths:
        card, field = read_card(path), load_field(path)
        config, arch = asdict(field.config), card["architecture"]
        assert {k: arch[k] for k in config} == config, path
        assert arch["parameters"] == sum(t.numel() for t in field.parameters()), path
        out = field.head(field.encode(torch.randn(1, 64, 3) * 0.05), torch.zeros(1, 4, 3))  # (1, 4, out_dim)
        assert out.shape == (1, 4, field.config.out_dim), path
    orders = [load_field(WEIGHTS_DIR / "table3" / f"nif-{n}.pt").config.scf_order for n in (1, 3, 5, 7, 10)]
    assert orders == [1, 3, 5, 7, 10]


# Thresholds from the shipped fields on this 24-sample draw of unseen instances, fed 1,024-point clouds
# as the cell's are: NIF R^2 0.47 when the encoder subsamples to its training size (512), 0.36 when it
# took all points - require 0.42; NDF accuracy 0.876 -> require 0.855 and 1 point above what guessing
# "all empty" scores on the same draw (about 0.85).
NIF_R2_MIN = 0.42
NDF_ACC_MIN = 0.855


def test_a_large_cloud_is_encoded_from_a_fixed_subset_of_the_training_size(test_split_data):
    field = load_field("nif")
    clouds = torch.as_tensor(test_split_data.cloud[:2])  # (2, 1024, 3)
    subset = field.subsample(clouds)
    assert subset.shape == (2, field.config.cloud_points, 3)
    assert torch.cdist(subset[1], clouds[1]).min(dim=1).values.max() == 0  # points of the cloud itself
    assert len(torch.unique(subset[1], dim=0)) == field.config.cloud_points  # no point twice
    with torch.no_grad():
        assert torch.allclose(field.encode(clouds).z[1], field.encode(clouds[1]).z[0], atol=1e-5)  # alone or batched


def test_shipped_nif_predicts_scf_on_unseen_objects(test_split_data):
    metrics = evaluate(load_field("nif"), test_split_data, np.arange(test_split_data.n_samples), 1024, 500)
    assert metrics["scf_r2"] > NIF_R2_MIN, metrics


def test_shipped_ndf_predicts_occupancy_on_unseen_objects(test_split_data):
    metrics = evaluate(load_field("ndf"), test_split_data, np.arange(test_split_data.n_samples), 1024, 500)
    assert metrics["occ_accuracy"] > NDF_ACC_MIN, metrics
    assert metrics["occ_accuracy"] > 1.0 - metrics["occupied_share"] + 0.01, metrics  # beats "all empty"
