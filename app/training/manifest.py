"""The manifest of a `nift make-data` directory, readable without the generator's dependencies.

Training reads data with torch and numpy alone (Open3D, trimesh and PyBullet make the data, they
are not needed to learn from it), so a GPU box with only torch can run `nift train`.
"""
from __future__ import annotations

import json
from pathlib import Path

FORMAT = "nift-data/1"


def read_manifest(out: Path) -> dict | None:
    """The manifest of a data directory, or None if there is none yet."""
    path = Path(out) / "manifest.json"
    if not path.is_file():
        return None
    try:
        manifest = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path} is not valid JSON ({exc.msg})") from None
    if manifest.get("format") != FORMAT:
        raise ValueError(f"{path}: expected format {FORMAT!r}, found {manifest.get('format')!r}")
    return manifest
