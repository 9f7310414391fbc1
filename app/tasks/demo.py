"""A recorded demonstration and its file (format nift-demo/1: an .npz with a JSON header).

A demo holds what an operator's teach-in leaves behind: the single-view object cloud the camera
saw (base frame), the camera's intrinsics and extrinsics, the object's category / seed / scale /
pose, the grasp (T_base_tcp), the place (T_fixture_obj: the object relative to the rack or
shelf) and the fixture's pose in the base frame.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from app.io_utils import read_npz, write_npz
from hardware.se3 import invert

FORMAT = "nift-demo/1"
DEMOS_DIR = Path(__file__).resolve().parents[2] / "demos"  # the shipped tasks' directories
DEMO_GLOB = "demo-*.npz"  # a task directory's demo files
POSES = ("T_base_obj", "T_base_tcp", "T_fixture_obj", "T_base_fixture", "T_base_cam")


@dataclass
class Demo:
    """One verified demonstration of a task."""

    task: str
    cloud: np.ndarray  # (N, 3) base frame
    T_base_obj: np.ndarray
    T_base_tcp: np.ndarray  # grasp
    T_fixture_obj: np.ndarray  # place, relative to the fixture
    T_base_fixture: np.ndarray
    T_base_cam: np.ndarray
    intrinsics: dict  # width, height, fx, fy, cx, cy
    category: str
    seed: int
    scale: float
    name: str = ""
    verdicts: dict = field(default_factory=dict)
    object: str = ""  # an imported object's library name ("": the procedural category-seed)
    taught: str = "teacher"  # who set the poses: "teacher" (scripted), "file" (a poses file) or "page" (nift teach --web)

    def grasp_anchor(self) -> np.ndarray:
        """The gripper's pose in the cloud's frame (for the grasp template)."""
        return self.T_base_tcp

    def place_anchor(self) -> np.ndarray:
        """Where the fixture would be, in the cloud's frame, for the object to sit as placed."""
        return self.T_base_obj @ invert(self.T_fixture_obj)


def intrinsics_record(K) -> dict:
    """A camera's intrinsics (`hardware.interfaces.CameraIntrinsics`) as a demo stores them."""
    return {k: getattr(K, k) for k in ("width", "height", "fx", "fy", "cx", "cy")}


def save_demo(demo: Demo, path: str | Path) -> Path:
    """Write a demo atomically."""
    header = {"format": FORMAT, "task": demo.task, "category": demo.category, "seed": demo.seed,
              "scale": demo.scale, "name": demo.name, "intrinsics": demo.intrinsics, "verdicts": demo.verdicts,
              "object": demo.object, "taught": demo.taught, **{k: np.asarray(getattr(demo, k)).tolist() for k in POSES}}
    return write_npz(path, {"cloud": np.asarray(demo.cloud, dtype=np.float32)}, header)


def load_demo(path: str | Path) -> Demo:
    """Read a demo; missing, corrupt, foreign and wrong-version files get a one-line error."""
    if not Path(path).is_file():
        raise FileNotFoundError(f"no demo at {path}")
    header, arrays = read_npz(path, FORMAT, "demo", ("cloud",))
    cloud = arrays["cloud"].astype(np.float64)
    try:
        poses = {k: np.array(header[k], dtype=np.float64).reshape(4, 4) for k in POSES}
        return Demo(header["task"], cloud, category=header["category"], seed=int(header["seed"]),
                    scale=float(header["scale"]), name=header.get("name", ""), intrinsics=header["intrinsics"],
                    verdicts=header.get("verdicts", {}), object=str(header.get("object", "")),
                    taught=str(header.get("taught", "teacher")), **poses)
    except (KeyError, ValueError, TypeError) as exc:
        raise ValueError(f"{path}: demo header is incomplete ({exc})") from None
