"""The CURVE keys of the device services (ZeroMQ's CurveZMQ, through pyzmq's `zmq.auth`): one key
pair for the server, one per client machine, and the server's list of allowed client keys.

A key folder (default `~/.config/nift/keys`, mode 0700) holds

    server.key, server.key_secret   the server's pair (the secret file mode 0600)
    client.key, client.key_secret   this machine's client pair
    clients/NAME.key                the public keys the server accepts (this machine's own, at first)

The files are pyzmq's certificate format (`zmq.auth.create_certificates`), so `zmq.auth` loads them.
A client elsewhere needs the server's `server.key` in its own folder; the server needs the client's
`client.key` in `clients/` (`nift serve --add-client FILE`).
"""
from __future__ import annotations

import os
import shutil
import stat
import tempfile
from dataclasses import dataclass
from pathlib import Path

import zmq
import zmq.auth

DEFAULT_KEY_DIR = Path.home() / ".config" / "nift" / "keys"
PAIRS = ("server", "client")


class KeyFileError(ValueError):
    """A key file that is missing, unreadable, not a key, or readable by others."""


@dataclass(frozen=True)
class ServerKeys:
    """The server's pair and the folder of client public keys it accepts."""

    public: bytes
    secret: bytes
    clients: Path


@dataclass(frozen=True)
class ClientKeys:
    """A client's pair and the public key of the server it trusts."""

    public: bytes
    secret: bytes
    server: bytes


def make_keys(folder: Path = DEFAULT_KEY_DIR) -> list[Path]:
    """Create what is missing of `folder` (see the module docstring); the files written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    (folder / "clients").mkdir(exist_ok=True, mode=0o700)
    written = [p for name in PAIRS if not (folder / f"{name}.key_secret").exists() for p in _make_pair(folder, name)]
    own = folder / "clients" / "this-machine.key"
    if not own.exists():
        _copy_atomically(folder / "client.key", own)
        written.append(own)
    return written


def _make_pair(folder: Path, name: str) -> list[Path]:
    """A new pair NAME.key / NAME.key_secret, made in a private temporary folder and moved in (atomic)."""
    with tempfile.TemporaryDirectory(dir=folder, prefix=".new-") as tmp:  # mkdtemp: mode 0700
        public, secret = (Path(p) for p in zmq.auth.create_certificates(tmp, name))
        secret.chmod(0o600)
        os.replace(secret, folder / secret.name)  # the secret first: a public key alone is never left
        os.replace(public, folder / public.name)
    return [folder / f"{name}.key", folder / f"{name}.key_secret"]


def _copy_atomically(source: Path, target: Path) -> None:
    tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    shutil.copyfile(source, tmp)
    os.replace(tmp, target)


def public_key(path: Path) -> bytes:
    """The public key in a key file (z85), or a one-line error naming the file."""
    return _load(Path(path), secret=False)[0]


def add_client(folder: Path, public_key_file: Path) -> Path:
    """Allow the client whose public key file is given: copied into `folder/clients/` under its name."""
    public_key_file = Path(public_key_file)
    public_key(public_key_file)  # a key file, or a one-line error
    target = Path(folder) / "clients" / f"{public_key_file.stem}.key"
    if not target.parent.is_dir():
        raise KeyFileError(f"no key folder {folder} (nift serve --make-keys makes one)")
    _copy_atomically(public_key_file, target)
    return target


def server_keys(folder: Path = DEFAULT_KEY_DIR) -> ServerKeys:
    """The server's keys in `folder`, or a one-line error naming the file."""
    folder = Path(folder)
    public, secret = _load(folder / "server.key_secret", secret=True)
    clients = folder / "clients"
    if not clients.is_dir() or not any(clients.glob("*.key")):
        raise KeyFileError(f"no client keys in {clients}: no client could connect (nift serve --add-client FILE)")
    return ServerKeys(public, secret, clients)


def client_keys(folder: Path = DEFAULT_KEY_DIR) -> ClientKeys:
    """This machine's client keys and the server's public key in `folder`, or a one-line error."""
    folder = Path(folder)
    public, secret = _load(folder / "client.key_secret", secret=True)
    server, _ = _load(folder / "server.key", secret=False)
    return ClientKeys(public, secret, server)


def _load(path: Path, secret: bool) -> tuple[bytes, bytes | None]:
    if not path.is_file():
        hint = " (nift serve --make-keys makes the keys)" if secret or path.name == "server.key" else ""
        raise KeyFileError(f"no key file {path}{hint}")
    mode = stat.S_IMODE(path.stat().st_mode)
    if secret and mode & 0o077:
        raise KeyFileError(f"secret key file {path} is readable by others (mode {mode:o}); chmod 600 it")
    try:
        public, private = zmq.auth.load_certificate(path)
    except (ValueError, OSError, UnicodeDecodeError) as exc:
        raise KeyFileError(f"{path} is not a CURVE key file ({' '.join(str(exc).split())[:80]})") from None
    if len(public or b"") != 40 or (secret and len(private or b"") != 40):
        raise KeyFileError(f"{path} holds no {'secret' if secret else 'public'} CURVE key")
    return public, private


def as_server(socket: zmq.Socket, keys: ServerKeys) -> None:
    """Make `socket` a CURVE server (before it binds)."""
    socket.curve_secretkey, socket.curve_publickey, socket.curve_server = keys.secret, keys.public, True


def as_client(socket: zmq.Socket, keys: ClientKeys) -> None:
    """Make `socket` a CURVE client of the server whose key it trusts (before it connects)."""
    socket.curve_secretkey, socket.curve_publickey, socket.curve_serverkey = keys.secret, keys.public, keys.server
