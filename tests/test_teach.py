"""Teach-in end to end in the sim cell, and imitation from the command line."""
import json

import numpy as np
import pytest

from app.cli import main
from app.cloud_io import load_cloud
from app.nift.template import load_template
from app.objects.fixtures import SHELF_SIZE, SHELF_TOP
from app.simcell.cell import CellConfig
from app.tasks.demo import load_demo
from app.tasks.demo_library import DEMOS_DIR, task_demos


@pytest.mark.slow
def test_teach_records_verified_demos_and_imitate_uses_them(tmp_path, capsys):
    out, calibration = tmp_path / "bottle", tmp_path / "calibration.json"
    assert main(["teach", "--task", "bottle", "--demos", "1", "--out", str(out), "--calibration", str(calibration),
                 "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["demos"] == 1 and calibration.is_file()
    demo = load_demo(out / "demo-00.npz")
    assert demo.verdicts["grasp"].startswith("held") and demo.verdicts["place"] == "resting on the fixture"
    # the cloud is the object: its centroid lies within the object's size of the object's origin
    assert np.linalg.norm(demo.cloud.mean(axis=0)[:2] - demo.T_base_obj[:2, 3]) < 0.05
    assert load_template(out / "grasp-ibs-nif.nit.npz").anchor == "gripper"
    assert load_template(out / "place-ibs-nif.nit.npz").anchor == "shelf"

    cloud = tmp_path / "target.ply"
    assert main(["capture", "--category", "bottle", "--out", str(cloud), "--image", str(tmp_path / "rgb.png"),
                 "--calibration", str(calibration), "--json"]) == 0
    capsys.readouterr()
    points = load_cloud(cloud)  # (N, 3) the unseen upright bottle, base frame
    board_xy, board_half = CellConfig().fixture_pose("shelf")[:2, 3], SHELF_SIZE[0] / 2
    for method in ("nift", "cpd"):
        assert main(["imitate", "--task", "bottle", "--cloud", str(cloud), "--demos", str(out), "--method", method,
                     "--iterations", "60", "--json"]) == 0
        pred = json.loads(capsys.readouterr().out)
        assert pred["method"] == method
        # the grasp is on the bottle: the TCP within a neck's radius of the cloud
        T_grasp = np.array(pred["T_base_tcp"])
        assert np.linalg.norm(points - T_grasp[:3, 3], axis=1).min() < 0.03, method
        # the place motion sets the bottle upright on the shelf board, resting on its top
        motion = np.array(pred["motion"])
        placed = points @ motion[:3, :3].T + motion[:3, 3]
        assert np.all(np.abs(placed.mean(axis=0)[:2] - board_xy) < board_half), method
        assert abs(placed[:, 2].min() - SHELF_TOP) < 0.025, method
        assert motion[2, 2] > np.cos(np.radians(30)), method  # the bottle's up stays up


def test_imitate_refuses_bad_input(tmp_path, capsys):
    assert main(["imitate", "--task", "mug", "--cloud", str(tmp_path / "none.ply")]) == 2
    assert "no point cloud" in capsys.readouterr().err
    np.save(tmp_path / "c.npy", np.zeros((100, 3)))  # 100 copies of one point
    assert main(["imitate", "--task", "mug", "--cloud", str(tmp_path / "c.npy")]) == 2
    assert "has 1 distinct points" in capsys.readouterr().err
    np.save(tmp_path / "c.npy", task_demos(DEMOS_DIR / "mug")[0].cloud)
    assert main(["imitate", "--task", "mug", "--cloud", str(tmp_path / "c.npy"), "--demos", str(tmp_path)]) == 2
    assert "no demos in" in capsys.readouterr().err
