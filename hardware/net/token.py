"""The shared token every connection authenticates with: a file of mode 0600, written on first serve."""
from __future__ import annotations

import os
import secrets
import stat
from pathlib import Path

DEFAULT_TOKEN_FILE = Path.home() / ".config" / "nift" / "device-token"


def read_token(path: Path = DEFAULT_TOKEN_FILE) -> str:
    """The token in `path`; a one-line error if it is missing, empty, or readable by others."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no device token file {path} (nift serve writes one on its first start)")
    mode = stat.S_IMODE(path.stat().st_mode)
    if mode & 0o077:
        raise PermissionError(f"device token file {path} is readable by others (mode {mode:o}); chmod 600 it")
    token = path.read_text().strip()
    if len(token) < 16:
        raise ValueError(f"device token file {path} holds no token of at least 16 characters")
    return token


def ensure_token(path: Path = DEFAULT_TOKEN_FILE) -> str:
    """The token in `path`, written first (mode 0600, created atomically) if the file does not exist."""
    path = Path(path)
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        token = secrets.token_urlsafe(32)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "w") as f:
            f.write(token + "\n")
        os.replace(tmp, path)
    return read_token(path)
