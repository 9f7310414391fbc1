"""The calibration file: versioned JSON, written atomically, validated on load."""
from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np

FORMAT = "nift-calibration/1"


def save_calibration(path: str | Path, T_base_cam: np.ndarray, info: dict) -> Path:
    """Write T_base_cam and free-form info (residuals, views, date) as JSON, atomically."""
    path = Path(path)
    T = np.asarray(T_base_cam, dtype=np.float64)
    if T.shape != (4, 4) or not np.isfinite(T).all():
        raise ValueError("T_base_cam must be a finite 4x4 pose")
    data = {"format": FORMAT, "T_base_cam": T.tolist(), **info}
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    with os.fdopen(fd, "w") as f:
        json.dump(data, f, indent=2)
    os.chmod(tmp, 0o644)
    os.replace(tmp, path)
    return path


def load_calibration(path: str | Path) -> tuple[np.ndarray, dict]:
    """(T_base_cam, the whole record) from a calibration file, or a one-line error naming the problem."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no calibration file (run `nift calibrate --out {path}`)")
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not a calibration file (invalid JSON: {exc.msg})") from exc
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        found = data.get("format") if isinstance(data, dict) else None
        raise ValueError(f"{path}: calibration format {found!r} is not {FORMAT!r}")
    T = np.asarray(data.get("T_base_cam"), dtype=np.float64)
    if T.shape != (4, 4) or not np.isfinite(T).all() or not np.allclose(T[3], [0, 0, 0, 1]):
        raise ValueError(f"{path}: T_base_cam is not a 4x4 homogeneous pose")
    R = T[:3, :3]
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
        raise ValueError(f"{path}: T_base_cam's rotation is not orthonormal")
    return T, data
