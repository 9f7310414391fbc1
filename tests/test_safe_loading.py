"""No code from files: a pickle payload planted in each loader's input is refused in one line and
never runs (it would touch a marker file), and weights without a state are refused too."""
import json
import pathlib

import numpy as np
import pytest
import torch


class Payload:
    """Unpickling this touches `marker`: proof that the loader ran code from the file."""

    def __init__(self, marker: pathlib.Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return pathlib.Path.touch, (self.marker,)


def _npz(path, marker, **arrays):
    np.savez(path, payload=np.array([Payload(marker)], dtype=object), **arrays)
    return path


def _cloud(tmp_path, marker):
    from app.cloud_io import load_cloud
    np.save(tmp_path / "c.npy", np.array([Payload(marker)], dtype=object), allow_pickle=True)
    return lambda: load_cloud(tmp_path / "c.npy")


def _demo(tmp_path, marker):
    from app.tasks.demo import load_demo
    header = np.array(json.dumps({"format": "nift-demo/1"}))
    _npz(tmp_path / "demo-00.npz", marker, header=header, cloud=np.array([Payload(marker)], dtype=object))
    return lambda: load_demo(tmp_path / "demo-00.npz")


def _template(tmp_path, marker):
    from app.nift.template import load_template
    header = np.array(json.dumps({"format": "nift-nit/2"}))
    _npz(tmp_path / "t.nit.npz", marker, header=header, points=np.array([Payload(marker)], dtype=object))
    return lambda: load_template(tmp_path / "t.nit.npz")


def _shard(tmp_path, marker):
    from app.training.dataset import FieldData
    from app.training.manifest import FORMAT
    data = tmp_path / "data"
    data.mkdir()
    _npz(data / "shard-00000.npz", marker, category=np.array([Payload(marker)], dtype=object))
    (data / "manifest.json").write_text(json.dumps({"format": FORMAT, "config": {}, "complete": True,
                                                    "shards": [{"file": "shard-00000.npz"}]}))
    return lambda: FieldData(data)


def _weights(tmp_path, marker):
    from app.nift.field import load_field
    torch.save({"format": "x", "state": Payload(marker)}, tmp_path / "w.pt")
    return lambda: load_field(tmp_path / "w.pt")


@pytest.mark.parametrize("plant", [_cloud, _demo, _template, _shard, _weights])
def test_a_pickle_payload_in_a_loaders_input_is_refused_and_never_runs(tmp_path, plant):
    marker = tmp_path / "ran"
    load = plant(tmp_path, marker)
    with pytest.raises(ValueError) as caught:
        load()
    assert not marker.exists() and "\n" not in str(caught.value)


def test_weights_with_an_empty_state_are_refused_in_one_line(tmp_path):
    from app.nift.field import FORMAT, load_field
    torch.save({"format": FORMAT, "config": {}, "state": {}}, tmp_path / "empty.pt")
    with pytest.raises(ValueError, match="non-empty state"):
        load_field(tmp_path / "empty.pt")
    torch.save({"format": FORMAT, "config": {}, "state": {"w": torch.zeros(1)}}, tmp_path / "wrong.pt")
    with pytest.raises(ValueError, match="do not fit their config"):
        load_field(tmp_path / "wrong.pt")


def test_a_demo_with_a_damaged_npy_header_is_refused_in_one_line(tmp_path):
    """A zeroed byte in an .npz member's header makes np.load raise tokenize.TokenError (the header is
    parsed as a Python literal), found by the property tests: it is a corrupt file like any other."""
    from pathlib import Path

    from app.tasks.demo import load_demo

    data = bytearray((Path(__file__).resolve().parents[1] / "demos/mug/demo-00.npz").read_bytes())
    data[127] = 0
    (tmp_path / "demo-00.npz").write_bytes(bytes(data))
    with pytest.raises(ValueError, match="not a readable demo file"):
        load_demo(tmp_path / "demo-00.npz")
