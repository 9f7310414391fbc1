"""Demo files and user clouds: round trips, and clear refusals of bad files."""
import json

import numpy as np
import pytest

from app.cloud_io import load_cloud, save_cloud
from app.tasks.demo import Demo, load_demo, save_demo
from hardware.se3 import invert, random_poses


def a_demo():
    rng = np.random.default_rng(0)
    T = random_poses(5, rng)
    return Demo("mug", rng.normal(size=(100, 3)), T[0], T[1], T[2], T[3], T[4],
                {"width": 512, "height": 424, "fx": 365.0, "fy": 365.0, "cx": 255.0, "cy": 205.0},
                "mug", 42, 1.05, "demo-00", {"grasp": "ok", "place": "ok"})


def test_demo_round_trip_and_place_anchor(tmp_path):
    demo = a_demo()
    back = load_demo(save_demo(demo, tmp_path / "d.npz"))
    for k in ("T_base_obj", "T_base_tcp", "T_fixture_obj", "T_base_fixture", "T_base_cam"):
        np.testing.assert_allclose(getattr(back, k), getattr(demo, k))
    np.testing.assert_allclose(back.cloud, demo.cloud, atol=1e-6)
    assert (back.category, back.seed, back.scale, back.name) == ("mug", 42, 1.05, "demo-00")
    # the seen fixture pose puts the object at T_fixture_obj relative to it
    np.testing.assert_allclose(invert(back.place_anchor()) @ back.T_base_obj, demo.T_fixture_obj, atol=1e-12)


def test_bad_demo_files_are_refused(tmp_path):
    good = save_demo(a_demo(), tmp_path / "good.npz")
    with pytest.raises(FileNotFoundError, match="no demo"):
        load_demo(tmp_path / "missing.npz")
    (tmp_path / "trunc.npz").write_bytes(good.read_bytes()[:500])
    with pytest.raises(ValueError, match="not a readable demo file"):
        load_demo(tmp_path / "trunc.npz")
    np.savez(tmp_path / "foreign.npz", something=np.zeros(3))
    with pytest.raises(ValueError, match="not a readable demo file"):
        load_demo(tmp_path / "foreign.npz")
    with np.load(good) as z:
        header, cloud = json.loads(str(z["header"])), z["cloud"]
    np.savez(tmp_path / "v2.npz", header=np.array(json.dumps({**header, "format": "nift-demo/2"})), cloud=cloud)
    with pytest.raises(ValueError, match="expected format 'nift-demo/1'"):
        load_demo(tmp_path / "v2.npz")
    del header["T_base_tcp"]
    np.savez(tmp_path / "partial.npz", header=np.array(json.dumps(header)), cloud=cloud)
    with pytest.raises(ValueError, match="incomplete"):
        load_demo(tmp_path / "partial.npz")


def test_clouds_round_trip_and_bad_clouds_are_refused(tmp_path):
    cloud = np.random.default_rng(1).normal(size=(50, 3))
    np.testing.assert_allclose(load_cloud(save_cloud(tmp_path / "c.ply", cloud)), cloud, atol=1e-6)
    np.save(tmp_path / "c.npy", cloud)
    np.testing.assert_allclose(load_cloud(tmp_path / "c.npy"), cloud)
    with pytest.raises(FileNotFoundError, match="no point cloud"):
        load_cloud(tmp_path / "none.ply")
    (tmp_path / "c.obj").write_text("v 0 0 0\n")
    with pytest.raises(ValueError, match="unknown point cloud format"):
        load_cloud(tmp_path / "c.obj")
    np.save(tmp_path / "empty.npy", np.zeros((0, 3)))
    with pytest.raises(ValueError, match="empty"):
        load_cloud(tmp_path / "empty.npy")
    bad = cloud.copy()
    bad[3, 1] = np.nan
    np.save(tmp_path / "nan.npy", bad)
    with pytest.raises(ValueError, match="NaN"):
        load_cloud(tmp_path / "nan.npy")
