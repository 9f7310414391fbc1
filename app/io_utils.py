"""File helpers shared by everything that writes: atomic writes, so a crash never leaves half a file."""
from __future__ import annotations

import json
import os
import tempfile
import tokenize
import zipfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside `path`; on success rename it over `path`, on error delete it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.chmod(tmp_path, 0o644)  # mkstemp makes it private; a result file is for everyone
        os.replace(tmp_path, path)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


def cache_root() -> Path:
    """Where generated files are cached: $NIFT_CACHE or ~/.cache/nift-cell."""
    return Path(os.environ.get("NIFT_CACHE") or Path.home() / ".cache" / "nift-cell")


def writable_directory(path: str | Path, what: str) -> Path:
    """`path` if it is, or could be made, a directory this process can write; a one-line error if not."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ValueError(f"{what} {path} is a file; give a directory")
    existing = next(p for p in (path, *path.parents) if p.exists())
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ValueError(f"{what} {path}: {existing} is not writable")
    return path


def writable_file(path: str | Path, what: str) -> Path:
    """`path` if a file could be written there (its folder is, or could be made, a writable
    directory, and it is no directory itself); a one-line error naming it if not."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{what} {path} is a directory; give a file")
    blocking = next((p for p in path.parents if p.exists() and not p.is_dir()), None)
    if blocking is not None:
        raise ValueError(f"{what} {path}: {blocking} is a file, not a directory")
    writable_directory(path.parent, what)
    return path


def numbered(path: Path | None, i: int, count: int) -> Path | None:
    """The file of item i of `count` written to `path`: the path itself for one, NAME-00.EXT ... for several."""
    if path is None or count == 1:
        return path
    return path.with_name(f"{path.stem}-{i:02d}{path.suffix}")


def write_json(path: str | Path, data: dict) -> Path:
    """Write JSON atomically (indented, keys in insertion order)."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(data, indent=2) + "\n")
    return Path(path)


def write_npz(path: str | Path, arrays: dict, header: dict | None = None) -> Path:
    """Write arrays (and a JSON header, stored as the string array `header`) as one .npz, atomically."""
    import numpy as np

    if header is not None:
        arrays = {"header": np.array(json.dumps(header)), **arrays}
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)
    return Path(path)


# What np.load raises for a corrupt, truncated or foreign .npy / .npz: its header is parsed as a Python
# literal, so a damaged byte there surfaces as SyntaxError or tokenize.TokenError, not ValueError.
NPY_ERRORS = (zipfile.BadZipFile, ValueError, KeyError, OSError, EOFError, SyntaxError, tokenize.TokenError)


def read_npz(path: str | Path, fmt: str, kind: str, names: tuple[str, ...]) -> tuple[dict, dict]:
    """(header, arrays) of an existing file written by write_npz; a corrupt, foreign or wrong-format
    file gets a one-line error naming `kind` (e.g. "demo") and the file."""
    import numpy as np

    try:
        with np.load(path, allow_pickle=False) as z:
            header = json.loads(str(z["header"]))
            found = header.get("format") if isinstance(header, dict) else None
            if found != fmt:  # before the arrays: another version may name other ones
                raise WrongFormat(f"{path}: expected format {fmt!r}, found {found!r}", found)
            arrays = {name: z[name] for name in names}
    except WrongFormat:
        raise
    except NPY_ERRORS as exc:
        raise ValueError(f"{path} is not a readable {kind} file ({type(exc).__name__})") from None
    return header, arrays


class WrongFormat(ValueError):
    """A readable file of another format or version (`found`: the format its header names)."""

    def __init__(self, message: str, found: object) -> None:
        super().__init__(message)
        self.found = found
