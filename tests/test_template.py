"""NIT files, multi-demo resampling, the 6-D rotation parametrisation, and imitation on known answers."""
import json

import numpy as np
import pytest
import torch

from app.nift.imitate import rotation_from_6d, rotation_to_6d
from app.nift.template import FORMAT, StaleTemplate, Template, density_resample, field_id, load_template, save_template
from hardware.se3 import random_rotations


def test_density_resampling_keeps_the_count_and_favours_where_demos_agree():
    rng = np.random.default_rng(0)
    agree = rng.normal(scale=0.002, size=(5, 100, 3)).reshape(-1, 3)  # 5 demos, same region
    stray = rng.uniform(-0.1, 0.1, size=(500, 3))  # where they disagree
    points = np.concatenate([agree, stray])
    out = density_resample(points, 500, k=5, rng=rng)
    assert out.shape == (500, 3) and len(np.unique(out, axis=0)) == 500  # no duplicates
    share = np.mean(np.linalg.norm(out, axis=1) < 0.01)
    assert share > 0.8  # the dense half of the input is > 80 % of the output
    with pytest.raises(ValueError, match="cannot resample"):
        density_resample(points[:10], 20, 2, rng)


def test_6d_rotations_are_proper_and_round_trip_even_at_180_degrees():
    R = torch.as_tensor(random_rotations(20, np.random.default_rng(1)))
    R[0] = torch.diag(torch.tensor([-1.0, -1.0, 1.0], dtype=R.dtype))  # 180 degrees about z
    back = rotation_from_6d(rotation_to_6d(R))
    assert torch.allclose(back, R, atol=1e-9)
    noisy = rotation_from_6d(torch.randn(50, 6, dtype=torch.float64))
    eye = torch.eye(3, dtype=torch.float64).expand(50, 3, 3)
    assert torch.allclose(noisy.transpose(1, 2) @ noisy, eye, atol=1e-9)
    assert torch.allclose(torch.linalg.det(noisy), torch.ones(50, dtype=torch.float64), atol=1e-9)


def fake_template(feature_dim=4, anchor="gripper"):
    rng = np.random.default_rng(0)
    return Template(rng.normal(size=(30, 3)), rng.normal(size=(30, feature_dim)).astype(np.float32), anchor,
                    "ibs", "nif", field_id("nif"), ["demo-0"], rng.uniform(0, 0.1, 30))


def test_template_files_round_trip_and_bad_files_are_refused(tmp_path):
    t = fake_template()
    path = save_template(t, tmp_path / "t.nit.npz")
    back = load_template(path)
    assert np.allclose(back.points, t.points, atol=1e-6) and np.array_equal(back.features, t.features)
    assert np.allclose(back.distances, t.distances, atol=1e-7)
    assert (back.anchor, back.query, back.feature, back.demos) == ("gripper", "ibs", "nif", ["demo-0"])
    with pytest.raises(FileNotFoundError, match="no template"):
        load_template(tmp_path / "missing.npz")
    (tmp_path / "garbage.npz").write_bytes(b"\x00" * 100)
    with pytest.raises(ValueError, match="not a readable NIT file"):
        load_template(tmp_path / "garbage.npz")
    (tmp_path / "short.npz").write_bytes(path.read_bytes()[:300])
    with pytest.raises(ValueError, match="not a readable NIT file"):
        load_template(tmp_path / "short.npz")
    with np.load(path) as z:
        header = json.loads(str(z["header"]))
        arrays = {k: z[k] for k in ("points", "features", "distances")}
    for change, message in (({"format": "nift-nit/0"}, "expected format"),
                            ({"field": "nif:000000000000"}, "was built with field")):
        bad = tmp_path / "bad.npz"
        np.savez(bad, header=np.array(json.dumps({**header, **change})), **arrays)
        with pytest.raises(ValueError, match=message):
            load_template(bad)
    old = tmp_path / "v1.npz"  # the first version had no distances: stale, so it is rebuilt from its demos
    np.savez(old, header=np.array(json.dumps({**header, "format": "nift-nit/1"})), **arrays)
    with pytest.raises(StaleTemplate, match="rebuild it from its demos"):
        load_template(old)
    assert FORMAT == "nift-nit/2"


def test_templates_of_other_nif_weights_sit_beside_the_shipped_ones(tmp_path):
    """`nift bench --nif W` (Table III): templates built and imitated with W, named by W's hash."""
    import shutil

    from app.bench.protocol import BenchConfig
    from app.bench.runner import settings
    from app.nift.field import FieldConfig, NeuralField, save_field
    from app.nift.imitate import ImitationConfig
    from app.predict.config import PredictConfig
    from app.predict.predict import predict
    from app.tasks.demo_library import DEMOS_DIR, task_demos, task_templates, template_path
    from app.tasks.task import task

    small = FieldConfig(scf_order=3, latent=8, encoder_width=8, encoder_blocks=1, decoder_width=16, decoder_blocks=1)
    weights = save_field(NeuralField(small), tmp_path / "order3.pt")
    t = task("bottle")
    demos = tmp_path / t.demos
    demos.mkdir()
    for path in sorted((DEMOS_DIR / t.demos).glob("demo-*.npz"))[:2]:
        shutil.copy2(path, demos / path.name)
    templates = task_templates(t, demos, "ibs", "nif", nif=weights)
    assert templates["grasp"].features.shape[1] == small.feature_dim  # not the shipped 449
    path = template_path(demos, "grasp", "ibs", "nif", weights)
    assert path.is_file() and path != template_path(demos, "grasp", "ibs", "nif")
    with pytest.raises(ValueError, match="rebuild it"):
        load_template(path)  # checked against the shipped NIF: refused
    cloud = task_demos(demos)[0].cloud
    pred = predict(t, cloud, PredictConfig(method="ibs-nif", demos=demos, fields=weights,
                                           imitation=ImitationConfig(inits=2, iterations=3), carried_grasps=False))
    assert pred.T_base_tcp.shape == (4, 4)
    assert settings(BenchConfig(nif=str(weights)))["nif_id"] == field_id(weights)
    with pytest.raises(FileNotFoundError, match="no field weights at"):
        settings(BenchConfig(nif=str(tmp_path / "missing.pt")))  # `nift bench --nif` with a wrong path
    # a template left from other weights (the shipped field was retrained) is rebuilt from the demos
    import dataclasses
    shipped = task_templates(t, demos, "ibs", "nif")["grasp"]
    save_template(dataclasses.replace(shipped, field_id="nif:000000000000"), template_path(demos, "grasp", "ibs", "nif"))
    assert task_templates(t, demos, "ibs", "nif")["grasp"].field_id == field_id("nif")
    assert load_template(template_path(demos, "grasp", "ibs", "nif")).field_id == field_id("nif")


def test_a_template_header_without_its_anchor_is_named(tmp_path):
    from app.io_utils import read_npz, write_npz
    from app.nift.template import FORMAT, load_template

    from pathlib import Path

    shipped = Path(__file__).resolve().parents[1] / "demos/mug/grasp-ibs-nif.nit.npz"
    header, arrays = read_npz(shipped, FORMAT, "NIT", ("points", "features", "distances"))
    del header["anchor"]
    write_npz(tmp_path / "t.nit.npz", arrays, header)
    with pytest.raises(ValueError, match="lacks anchor"):
        load_template(tmp_path / "t.nit.npz")


def test_templates_the_project_does_not_ship_are_built_in_the_cache_not_in_demos(tmp_path, monkeypatch):
    """A baseline's templates for the shipped demos go to $NIFT_CACHE/templates/<task>-<digest of the
    demos>/, are read from there the next time, and nothing is written into demos/."""
    import time

    from app.tasks.demo_library import DEMOS_DIR, built_elsewhere, task_templates
    from app.tasks.task import task

    monkeypatch.setenv("NIFT_CACHE", str(tmp_path))
    before = sorted(p.name for p in (DEMOS_DIR / "bowl").iterdir())
    first = task_templates(task("bowl"), query="bps", feature="scf")
    where = built_elsewhere(DEMOS_DIR / "bowl")
    assert where.parent == tmp_path / "templates" and sorted(p.name for p in where.iterdir()) == [
        "grasp-bps-scf.nit.npz", "place-bps-scf.nit.npz"]
    assert sorted(p.name for p in (DEMOS_DIR / "bowl").iterdir()) == before
    stamps = {p: p.stat().st_mtime_ns for p in where.iterdir()}
    time.sleep(0.01)
    again = task_templates(task("bowl"), query="bps", feature="scf")
    assert {p: p.stat().st_mtime_ns for p in where.iterdir()} == stamps  # read, not rebuilt
    assert np.allclose(first["grasp"].features, again["grasp"].features)
