"""The UR5's description: its home pose, and its URDF from the installed example-robot-data package
(never copied here), assembled with our gripper.

example-robot-data 6.x ships no Python module; its files are under
`<site-packages>/cmeel.prefix/share/example-robot-data/robots/`. URDFs there use `package://`
mesh URIs, which PyBullet cannot resolve, so `resolved_urdf` writes a copy with absolute paths
into a cache directory.
"""
from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

import numpy as np

from hardware.gripper_geometry import GripperGeometry, gripper_urdf_fragment

ROBOTS_SUBDIR = Path("cmeel.prefix") / "share" / "example-robot-data" / "robots"
UR5_URDF = Path("ur_description") / "urdf" / "ur5_robot.urdf"
HOME_Q = np.array([np.pi, -2.2, 1.9, -1.27, -1.57, 0.0])  # TCP pointing down at (0.22, 0.11, 0.37), clear of the camera crop


def robots_dir() -> Path:
    """The example-robot-data `robots/` directory in this environment's site-packages."""
    for entry in sys.path:
        candidate = Path(entry) / ROBOTS_SUBDIR
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError("example-robot-data is not installed (no cmeel.prefix/share/example-robot-data "
                            "in site-packages); run scripts/install.sh")


def ur5_urdf() -> Path:
    """Path of the installed UR5 URDF (with package:// mesh URIs)."""
    path = robots_dir() / UR5_URDF
    if not path.exists():
        raise FileNotFoundError(f"{path}: UR5 URDF missing from example-robot-data")
    return path


def cache_dir() -> Path:
    """Writable cache for generated files: $NIFT_CACHE or ~/.cache/nift-cell."""
    return Path(os.environ.get("NIFT_CACHE") or Path.home() / ".cache" / "nift-cell")


def resolve_packages(urdf_text: str) -> str:
    """Replace `package://example-robot-data/robots/` URIs with absolute paths."""
    return urdf_text.replace("package://example-robot-data/robots/", f"{robots_dir().as_posix()}/")


def write_cached(name: str, text: str) -> Path:
    """Write text to the cache under a content-hashed name (atomic); return the path."""
    digest = hashlib.sha1(text.encode()).hexdigest()[:12]
    path = cache_dir() / "urdf" / f"{name}-{digest}.urdf"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(text)
        os.replace(tmp, path)
    return path


def cell_robot_urdf(geometry: GripperGeometry = GripperGeometry()) -> str:
    """UR5 URDF text with absolute mesh paths and the gripper attached at tool0."""
    text = resolve_packages(ur5_urdf().read_text())
    cut = text.rindex("</robot>")
    return text[:cut] + gripper_urdf_fragment(geometry) + "\n" + text[cut:]
