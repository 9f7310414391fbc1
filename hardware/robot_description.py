"""Where the UR5 description lives: the installed example-robot-data package (never copied here).

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

ROBOTS_SUBDIR = Path("cmeel.prefix") / "share" / "example-robot-data" / "robots"
UR5_URDF = Path("ur_description") / "urdf" / "ur5_robot.urdf"


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
