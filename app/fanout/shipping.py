"""Read-only folders and files carried to the nodes through Ray's object store.

The driver packs a folder (demos and their templates, a weights file) into a `Parcel`; the parcel
rides in the task's payload, which Ray stores once and copies once to each node that runs a task.
On the node, `landed` unpacks it under the temp directory, named by its digest, once: later tasks
and workers on that node find it there. Locally this costs one copy of small files; on a cluster
it is what lets a node without the user's files run the run.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

LIMIT_BYTES = 512 * 2**20  # a parcel larger than this is a mistake (a dataset folder), not demos or weights


@dataclass(frozen=True)
class Parcel:
    """A folder's (or one file's) bytes by relative path, and their digest."""

    name: str
    files: tuple[tuple[str, bytes], ...]
    digest: str


def pack(path: str | Path) -> Parcel:
    """A folder's regular files (recursively) or one file; a one-line error past LIMIT_BYTES."""
    path = Path(path)
    paths = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    if (size := sum(p.stat().st_size for p in paths)) > LIMIT_BYTES:
        raise ValueError(f"{path} holds {size / 2**20:.0f} MiB; more than {LIMIT_BYTES // 2**20} MiB is not shipped to workers")
    files = tuple((f"{path.name}/{p.relative_to(path).as_posix()}" if path.is_dir() else p.name, p.read_bytes())
                  for p in paths)
    digest = hashlib.sha256()
    for rel, data in files:
        digest.update(rel.encode() + b"\0" + hashlib.sha256(data).digest())
    return Parcel(path.name, files, digest.hexdigest()[:16])


def landing_root() -> Path:
    return Path(tempfile.gettempdir()) / "nift-shipped"


def landed(parcel: Parcel) -> Path:
    """The parcel's folder or file, unpacked on this node once (a racing worker's copy is discarded)."""
    home = landing_root() / parcel.digest
    if not home.is_dir():
        home.parent.mkdir(parents=True, exist_ok=True)
        scratch = Path(tempfile.mkdtemp(prefix=f".{parcel.digest}-", dir=home.parent))
        for rel, data in parcel.files:
            (scratch / rel).parent.mkdir(parents=True, exist_ok=True)
            (scratch / rel).write_bytes(data)
        try:
            os.rename(scratch, home)
        except OSError:  # another worker landed it first
            shutil.rmtree(scratch, ignore_errors=True)
    return home / parcel.name
