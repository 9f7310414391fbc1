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
    if not isinstance(manifest, dict) or not isinstance(manifest.get("shards", []), list):
        raise ValueError(f"{path}: expected a JSON object with a list of shards, found {type(manifest).__name__}")
    if manifest.get("format") != FORMAT:
        raise ValueError(f"{path}: expected format {FORMAT!r}, found {manifest.get('format')!r}")
    return manifest


def shard_path(out: Path, name: object) -> Path:
    """The file of a shard named in the manifest of `out`, which must lie inside `out` (a manifest
    naming `../elsewhere.npz` or an absolute path is refused in one line)."""
    root = Path(out).resolve()
    if not isinstance(name, str) or not name:
        raise ValueError(f"{Path(out) / 'manifest.json'}: a shard's file must be a name, got {name!r}")
    path = (root / name).resolve()
    if not path.is_relative_to(root):
        raise ValueError(f"{Path(out) / 'manifest.json'}: shard {name!r} lies outside {out}")
    return path
