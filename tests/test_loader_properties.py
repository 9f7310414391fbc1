"""Property-based tests (Hypothesis) of the loaders and the config parser: random bytes, random
truncations of good files and random valid-but-wrong values end in a one-line ValueError or
OSError, or load a value that obeys every rule - never another exception, never a wrong value."""
import json
import math
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app.cloud_io import load_cloud
from app.config import load_toml
from app.simcell.cell import CellConfig
from app.tasks.demo import load_demo
from app.nift.template import load_template
from calibration.store import load_calibration
from hardware.net import wire

ROOT = Path(__file__).resolve().parents[1]
EXPECTED = (ValueError, OSError)
FAST = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def _write(tmp_path: Path, name: str, data: bytes) -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


def _one_line(exc: BaseException) -> None:
    assert "\n" not in str(exc) and str(exc)


def _damaged(data: bytes):
    """A good file's bytes cut short at a random place, or with a few bytes overwritten at random."""
    truncated = st.integers(0, len(data) - 1).map(lambda n: data[:n])
    corrupted = st.lists(st.tuples(st.integers(0, len(data) - 1), st.integers(0, 255)), min_size=1, max_size=8).map(
        lambda edits: bytes(_apply(bytearray(data), edits)))
    return st.one_of(truncated, corrupted)


def _loaded(load, path: Path):
    """`load(path)`, or None when it refused the file in one line (anything else fails the test)."""
    try:
        return load(path)
    except EXPECTED as exc:
        _one_line(exc)
        return None


def _apply(data: bytearray, edits) -> bytearray:
    for i, b in edits:
        data[i] = b
    return data


@FAST
@given(data=st.binary(max_size=400))
def test_random_bytes_as_a_cell_toml(tmp_path, data):
    config = _loaded(lambda p: load_toml(CellConfig, p), _write(tmp_path, "cell.toml", data))
    assert config is None or isinstance(config, CellConfig)


SCALARS = st.one_of(st.booleans(), st.integers(-10**6, 10**6), st.floats(allow_nan=True, allow_infinity=True),
                    st.text(max_size=8))
RANGED = {("world", "time_step"): (0.0, 0.05), ("arm", "contact_force_limit"): (0.0, 10_000.0),
          ("arm", "tracking_error_limit"): (0.0, 1.0), ("gripper", "timeout"): (0.0, 60.0)}


@FAST
@given(values=st.dictionaries(st.sampled_from(sorted(RANGED)), SCALARS, min_size=1, max_size=4),
       noise=st.one_of(st.booleans(), st.integers(), st.text(max_size=5)))
def test_valid_toml_with_wrong_values_is_refused_or_obeys_every_range(tmp_path, values, noise):
    lines = [f"camera_noise = {json.dumps(noise)}"]
    for section in sorted({s for s, _ in values}):
        lines.append(f"[{section}]")
        for (sec, key), value in values.items():
            if sec == section:
                text = ("nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")) \
                    if isinstance(value, float) and not math.isfinite(value) else json.dumps(value)
                lines.append(f"{key} = {text}")
    config = _loaded(lambda p: load_toml(CellConfig, p), _write(tmp_path, "cell.toml", "\n".join(lines).encode()))
    if config is None:
        return
    assert isinstance(config.camera_noise, bool) and config.camera_noise == noise
    for (section, key), (low, high) in RANGED.items():
        got = getattr(getattr(config, section), key)
        assert isinstance(got, float) and not isinstance(got, bool) and low < got <= high
        if (section, key) in values:
            assert got == values[(section, key)]


def _ply_text(points: np.ndarray) -> bytes:
    body = "\n".join(f"{x} {y} {z}" for x, y, z in points)
    return (f"ply\nformat ascii 1.0\nelement vertex {len(points)}\nproperty float x\nproperty float y\n"
            f"property float z\nend_header\n{body}\n").encode()


def _calibration_bytes() -> bytes:
    """A calibration file as `nift calibrate` writes it (a true camera pose, a few figures)."""
    import tempfile

    from calibration.store import save_calibration
    from hardware.se3 import make_pose, rotvec_to_matrix

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "calibration.json"
        save_calibration(path, make_pose(rotvec_to_matrix([2.0, -0.3, 0.4]), [1.25, 0.0, 0.55]),
                         {"views": 20, "reprojection_rms_px": 0.21, "hand_eye_residual_mm": 0.8})
        return path.read_bytes()


CALIBRATION = _calibration_bytes()
GOOD_PLY = _ply_text(np.random.default_rng(0).normal(size=(200, 3)) * 0.03 + [0.5, 0.0, 0.05])


@FAST
@given(data=st.one_of(st.binary(max_size=600), st.integers(0, len(GOOD_PLY) - 1).map(lambda n: GOOD_PLY[:n]),
                      st.binary(max_size=60).map(lambda b: GOOD_PLY[:300] + b)))
def test_clouds_from_random_and_truncated_ply_files(tmp_path, data):
    cloud = _loaded(load_cloud, _write(tmp_path, "cloud.ply", data))
    if cloud is not None:
        assert cloud.ndim == 2 and cloud.shape[1] == 3 and len(cloud) > 0 and np.isfinite(cloud).all()


@FAST
@given(data=_damaged((ROOT / "demos/mug/demo-00.npz").read_bytes()))
def test_demos_truncated_or_corrupted(tmp_path, data):
    demo = _loaded(load_demo, _write(tmp_path, "demo-00.npz", data))
    if demo is not None:  # a byte changed inside the compressed data may still load: then it is a whole demo
        assert demo.cloud.ndim == 2 and demo.cloud.shape[1] == 3 and demo.T_base_tcp.shape == (4, 4)


@FAST
@given(data=_damaged((ROOT / "demos/mug/grasp-ibs-nif.nit.npz").read_bytes()))
def test_templates_truncated_or_corrupted(tmp_path, data):
    t = _loaded(load_template, _write(tmp_path, "grasp-ibs-nif.nit.npz", data))
    if t is not None:
        assert np.isfinite(t.features).all() and t.points.shape[0] == t.features.shape[0]


@FAST
@given(data=_damaged(CALIBRATION))
def test_calibration_files_truncated_or_corrupted(tmp_path, data):
    loaded = _loaded(load_calibration, _write(tmp_path, "calibration.json", data))
    if loaded is not None:
        T = loaded[0]
        assert T.shape == (4, 4) and np.isfinite(T).all()
        assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-3) and np.allclose(T[3], [0, 0, 0, 1])


@settings(max_examples=300, deadline=None)
@given(data=st.binary(max_size=300))
def test_random_bytes_on_the_wire_are_a_wire_error_or_a_map(data):
    try:
        message = wire.unpack(data)
    except wire.WireError as exc:
        _one_line(exc)
    else:
        assert isinstance(message, dict)
