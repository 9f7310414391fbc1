import json

import numpy as np
import pytest

from calibration.board import Detection
from calibration.eye_to_hand import Observation, solve
from calibration.store import FORMAT, load_calibration, save_calibration
from hardware.se3 import invert, make_pose, random_poses, rotation_angle
from hardware.sim.kinect import KINECT_V2_DEPTH

K = KINECT_V2_DEPTH.matrix


def synthetic_views(T_base_cam, T_tcp_board, n, rng, pixel_noise=0.0):
    """Views whose board corners are exactly (or noisily) where the true calibration puts them."""
    corners = np.array([[i * 0.05, j * 0.05, 0.0] for i in range(1, 5) for j in range(1, 4)])
    views = []
    for T_jitter in random_poses(n, rng, translation_scale=0.08):
        T_base_tcp = make_pose(np.eye(3), [0.6, 0.0, 0.3]) @ make_pose(_small(T_jitter[:3, :3]), T_jitter[:3, 3])
        T_cam_board = invert(T_base_cam) @ T_base_tcp @ T_tcp_board
        pc = corners @ T_cam_board[:3, :3].T + T_cam_board[:3, 3]
        uv = pc @ K.T
        uv = uv[:, :2] / uv[:, 2:3] + rng.normal(0, pixel_noise, (len(corners), 2))
        views.append(Observation(T_base_tcp, Detection(T_cam_board, corners, uv, 0.0)))
    return views


def _small(R):
    """Shrink a Haar rotation to at most ~20 degrees, keeping its axis."""
    from scipy.spatial.transform import Rotation

    v = Rotation.from_matrix(R).as_rotvec()
    return Rotation.from_rotvec(v * 0.35 / max(np.linalg.norm(v), 1e-9)).as_matrix()


def true_setup():
    from hardware.sim.kinect import look_at

    T_base_cam = look_at([1.25, 0.0, 0.55], [0.5, 0.0, 0.05])
    T_tcp_board = make_pose(np.diag([1.0, -1.0, -1.0]), [-0.125, 0.1, 0.025])
    return T_base_cam, T_tcp_board


def test_solve_recovers_exact_calibration(rng):
    T_base_cam, T_tcp_board = true_setup()
    result = solve(synthetic_views(T_base_cam, T_tcp_board, 12, rng), K)
    d = invert(T_base_cam) @ result.T_base_cam
    assert np.linalg.norm(d[:3, 3]) < 1e-6 and rotation_angle(d[:3, :3]) < 1e-6
    assert result.reprojection_rms_px < 1e-4


def test_solve_with_pixel_noise_stays_within_a_millimetre(rng):
    T_base_cam, T_tcp_board = true_setup()
    result = solve(synthetic_views(T_base_cam, T_tcp_board, 20, rng, pixel_noise=0.3), K)
    d = invert(T_base_cam) @ result.T_base_cam
    assert np.linalg.norm(d[:3, 3]) < 0.002 and np.degrees(rotation_angle(d[:3, :3])) < 0.2
    with pytest.raises(ValueError, match="at least 3 views"):
        solve([], K)


def test_sim_cell_calibration_recovers_the_camera():
    from app.simcell.calibration import calibrate_sim_cell
    from app.simcell.cell import SimCell

    with SimCell() as cell:
        c = calibrate_sim_cell(cell, views=20, seed=0)
    assert c.result.n_views >= 15
    assert c.error_mm < 2.0 and c.error_deg < 0.2, (c.error_mm, c.error_deg)
    assert c.result.reprojection_rms_px < 1.0


def test_calibration_file_round_trip_and_errors(tmp_path):
    T_base_cam, _ = true_setup()
    path = save_calibration(tmp_path / "cal.json", T_base_cam, {"views": 20})
    T, record = load_calibration(path)
    assert np.allclose(T, T_base_cam) and record["views"] == 20 and record["format"] == FORMAT
    with pytest.raises(FileNotFoundError, match="nift calibrate"):
        load_calibration(tmp_path / "missing.json")
    (tmp_path / "old.json").write_text(json.dumps({"format": "nift-calibration/0", "T_base_cam": T.tolist()}))
    with pytest.raises(ValueError, match="format 'nift-calibration/0'"):
        load_calibration(tmp_path / "old.json")
    (tmp_path / "junk.json").write_text("{not json")
    with pytest.raises(ValueError, match="invalid JSON"):
        load_calibration(tmp_path / "junk.json")
    bad = T.copy()
    bad[:3, :3] *= 2
    (tmp_path / "bad.json").write_text(json.dumps({"format": FORMAT, "T_base_cam": bad.tolist()}))
    with pytest.raises(ValueError, match="not orthonormal"):
        load_calibration(tmp_path / "bad.json")
