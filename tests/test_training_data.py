"""Field training data: camera views, labels, determinism, resume, and the make-data/train verbs."""
import json
from pathlib import Path

import numpy as np
import pytest

from app.cli import main
from app.nift.field import load_field
from app.nift.raycast import scene_of, unsigned_distance
from app.nift.scf import compute_scf
from app.objects import generate
from app.training.data import DataConfig, make_dataset, shard_name
from app.training.dataset import FieldData
from app.training.evaluate import evaluate
from app.training.views import camera_poses, kinect_cloud, observe
from hardware.sim.kinect import NoiseModel

TINY = DataConfig(instances=2, views=2, queries=200, shard_instances=2, seed=5)


def mug_scene():
    mesh = generate("mug", 3)
    center = mesh.bounds.mean(axis=0)
    return mesh, scene_of(mesh), center, float(np.linalg.norm(mesh.vertices - center, axis=1).max())


def test_windowed_rays_see_exactly_what_the_full_image_sees():
    _, scene, center, radius = mug_scene()
    for seed in range(3):
        T = camera_poses("single", np.eye(3), center, np.random.default_rng(seed))[0]
        full = kinect_cloud(scene, T, np.random.default_rng(0))
        window = kinect_cloud(scene, T, np.random.default_rng(0), sphere=(center, radius))
        assert len(full) > 300 and np.array_equal(full, window)


def test_noise_free_views_lie_on_the_surface_and_noise_is_millimetres():
    mesh, scene, center, radius = mug_scene()
    T = camera_poses("single", np.eye(3), center, np.random.default_rng(1))[0]
    exact = kinect_cloud(scene, T, np.random.default_rng(0), NoiseModel(enabled=False))
    noisy = kinect_cloud(scene, T, np.random.default_rng(0))
    assert unsigned_distance(scene, exact).max() < 0.0008  # only the 1 mm depth quantisation
    # same pixels in the same order; the range error along each ray is the Kinect's axial noise
    along = np.linalg.norm(noisy - T[:3, 3], axis=1) - np.linalg.norm(exact - T[:3, 3], axis=1)
    assert 0.0006 < along.std() < 0.002  # sigma(z ~ 0.7-1.1 m) = 0.8-1.3 mm plus quantisation
    # the camera sees one side: every point faces the camera
    assert np.all(np.linalg.norm(exact - T[:3, 3], axis=1) < np.linalg.norm(center - T[:3, 3]) + radius)


def test_fused_views_cover_more_of_the_object_than_one():
    mesh, scene, center, radius = mug_scene()
    rng = np.random.default_rng(0)
    surface = mesh.sample(3000, seed=1)
    for camera, lo, hi in (("single", 0.0, 0.65), ("fused", 0.75, 1.0)):
        cloud = observe(scene, camera, np.eye(3), center, radius, 1024, rng)
        assert cloud.shape == (1024, 3)
        near = np.min(np.linalg.norm(surface[:, None] - cloud[None, ::4], axis=-1), axis=1) < 0.01
        assert lo <= near.mean() <= hi, (camera, near.mean())


def test_make_data_is_deterministic_resumable_and_labels_are_right(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    report = make_dataset(TINY, a, workers=1, progress=False)
    assert report.figures()["samples"] == 3 * 2 * 2 and report.manifest["complete"]
    make_dataset(TINY, b, workers=1, progress=False)
    for i in range(3):
        assert (a / shard_name(i)).read_bytes() == (b / shard_name(i)).read_bytes()
    # interrupt: lose a shard, resume, get the same bytes back
    original = (a / shard_name(1)).read_bytes()
    (a / shard_name(1)).unlink()
    again = make_dataset(TINY, a, workers=1, progress=False)
    assert again.new_samples == 4 and (a / shard_name(1)).read_bytes() == original
    # labels: SCF recomputed from the mesh at the stored canonical points
    data = FieldData(a)
    cat, seed = TINY.categories[data.category[0]], int(data.seed[0])
    scf = compute_scf(generate(cat, seed), data.queries[0, :20], order=10)
    np.testing.assert_allclose(data.scf[0, :20].astype(np.float32), scf, rtol=2e-3, atol=2e-3)
    # a batch puts the queries in the sample's pose: x = R (s q), so |x| = s |q|
    batch = data.batch(np.array([0]), 64, 32, 5, np.random.default_rng(0))
    assert batch["scf"].shape == (1, 32, 6) and batch["cloud"].shape == (1, 64, 3)
    with pytest.raises(ValueError, match="different config"):
        make_dataset(DataConfig(instances=2, views=3, queries=200, shard_instances=2, seed=5), a, workers=1,
                     progress=False)


def test_bad_data_requests_are_refused(tmp_path):
    with pytest.raises(ValueError, match="unknown object category"):
        DataConfig(categories=("teapot",))
    with pytest.raises(ValueError, match="unknown camera setting"):
        DataConfig(camera="stereo")
    with pytest.raises(FileNotFoundError, match="nift make-data"):
        FieldData(tmp_path)
    (tmp_path / "manifest.json").write_text("{")
    with pytest.raises(ValueError, match="not valid JSON"):
        FieldData(tmp_path)


def test_make_data_and_train_verbs_quick(tmp_path, capsys):
    data = tmp_path / "data"
    assert main(["make-data", "--out", str(data), "--quick", "--workers", "1", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["samples"] == 3 * 3 * 2 and figures["complete"]
    assert main(["train", "--target", "occ", "--data", str(data), "--eval-data", str(data),
                 "--out", str(tmp_path / "run"), "--quick", "--json"]) == 0
    card = json.loads(capsys.readouterr().out)
    assert card["name"] == "NDF" and (tmp_path / "run" / "last.pt").is_file()
    # round trip: the saved weights, evaluated again on the same data, give the card's test figures
    field = load_field(tmp_path / "run" / "field.pt")
    test = FieldData(data)
    again = evaluate(field, test, np.arange(test.n_samples), test.cloud.shape[1], card["training"]["query_points"])
    assert again["occ_accuracy"] == card["test"]["occ_accuracy"] and again["loss"] == pytest.approx(card["test"]["loss"])
    assert again["occupied_share"] == pytest.approx(float(test.occ.mean()), abs=0.1)  # labels as made, drawn
    assert sum(p.numel() for p in field.parameters()) == card["architecture"]["parameters"]
    first_history = json.loads((tmp_path / "run" / "field.json").read_text())["history"]
    assert len(first_history) == 1
    # resume: a second run with one more epoch continues from the checkpoint instead of starting again
    assert main(["train", "--target", "occ", "--data", str(data), "--out", str(tmp_path / "run"),
                 "--quick", "--epochs", "2", "--resume", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["training"]["epochs"] == 2
    history = json.loads((tmp_path / "run" / "field.json").read_text())["history"]
    assert len(history) == 2 and history[0] == first_history[0]  # the first epoch is the one already trained


class _Payload:
    """What a planted checkpoint would run if it were unpickled unsafely: it touches a file."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


def test_resume_refuses_a_checkpoint_that_would_run_code(tmp_path, capsys):
    import torch

    data, run = tmp_path / "data", tmp_path / "run"
    assert main(["make-data", "--out", str(data), "--quick", "--workers", "1", "--json"]) == 0
    run.mkdir()
    marker = tmp_path / "ran"
    torch.save({"config": {}, "payload": _Payload(marker)}, run / "last.pt")
    assert main(["train", "--target", "occ", "--data", str(data), "--out", str(run), "--quick", "--resume", "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert "last.pt: not a checkpoint that loads safely" in err and len(err.splitlines()) == 1
    assert not marker.exists()  # the payload never ran


def test_a_manifest_cannot_name_a_shard_outside_its_directory(tmp_path):
    data = tmp_path / "data"
    make_dataset(TINY, data, workers=1)
    manifest = json.loads((data / "manifest.json").read_text())
    outside = tmp_path / "outside.npz"
    outside.write_bytes((data / manifest["shards"][0]["file"]).read_bytes())  # a valid shard, but elsewhere
    for name in ("../outside.npz", str(outside)):
        manifest["shards"][0]["file"] = name
        (data / "manifest.json").write_text(json.dumps(manifest))
        with pytest.raises(ValueError, match="lies outside"):
            FieldData(data)


def test_a_set_stopped_after_its_first_shard_is_refused_for_training_until_resumed(tmp_path, monkeypatch):
    import app.training.data as data_module

    data = tmp_path / "data"
    real = data_module.run_shards

    def stopped(*args, **kwargs):
        yield next(iter(real(*args, **kwargs)))
        raise KeyboardInterrupt  # killed once the first shard and its manifest line are written

    monkeypatch.setattr(data_module, "run_shards", stopped)
    with pytest.raises(KeyboardInterrupt):
        make_dataset(TINY, data, workers=1, progress=False)
    assert not json.loads((data / "manifest.json").read_text())["complete"]
    with pytest.raises(ValueError, match="is incomplete .*1 shards.*resume it"):
        FieldData(data)
    monkeypatch.setattr(data_module, "run_shards", real)
    assert make_dataset(TINY, data, workers=1, progress=False).manifest["complete"]
    assert FieldData(data).n_samples == 3 * 2 * 2
