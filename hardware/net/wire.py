"""The devices' wire format: one msgpack map per ZeroMQ message, numpy arrays as raw bytes.

Transport: pyzmq (ROUTER server, REQ client), as LeRobot's networked robots use it - a maintained
message library that frames, reconnects and queues for us. msgpack carries plain types; an array
is the extension type ARRAY holding [dtype, shape, bytes] for the few dtypes the devices use
(joint vectors, trajectories, depth and colour frames), so a 512 x 424 depth frame is its 868 kB
and not a JSON list. Nothing is ever unpickled: an unknown extension, dtype or size is refused.

    request  {"v": PROTOCOL, "client": str, "device": str, "verb": str, "args": [...]}
    reply    {"ok": true, "value": ...}  or  {"ok": false, "error": NAME, "message": str}
"""
from __future__ import annotations

from typing import Any

import msgpack
import numpy as np

PROTOCOL = 2  # 2: no token field (CURVE authenticates the connection)
ARRAY = 1  # msgpack extension code of a numpy array
DTYPES = ("<f8", "<f4", "|u1", "<u2", "<i8", "|b1")  # the only array types on the wire
MAX_MESSAGE = 16 * 1024 * 1024  # bytes: a larger request gets an error reply
MAX_ELEMENTS = 4 * 1024 * 1024  # per array


class WireError(ValueError):
    """A message that is not a valid message of this protocol."""


def _default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        a = np.ascontiguousarray(obj)
        if a.dtype.str not in DTYPES:
            a = a.astype(np.float64) if a.dtype.kind == "f" else a.astype("<i8")
        return msgpack.ExtType(ARRAY, msgpack.packb([a.dtype.str, list(a.shape), a.tobytes()]))
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"cannot send a {type(obj).__name__} over the wire")


def _ext_hook(code: int, data: bytes) -> np.ndarray:
    if code != ARRAY:
        raise WireError(f"unknown msgpack extension type {code}")
    try:
        dtype, shape, raw = msgpack.unpackb(data, raw=False, strict_map_key=True)
    except (ValueError, msgpack.ExtraData, TypeError) as exc:
        raise WireError(f"malformed array: {exc}") from None
    if dtype not in DTYPES or not isinstance(shape, list) or not all(isinstance(n, int) and n >= 0 for n in shape):
        raise WireError(f"unsupported array type {dtype!r} or shape {shape!r}")
    count = int(np.prod(shape)) if shape else 1
    if count > MAX_ELEMENTS or not isinstance(raw, bytes) or len(raw) != count * np.dtype(dtype).itemsize:
        raise WireError(f"array of {dtype} {shape} does not match its {len(raw) if isinstance(raw, bytes) else '?'} bytes")
    return np.frombuffer(raw, dtype=dtype).reshape(shape).copy()


def pack(message: dict) -> bytes:
    """A message as bytes."""
    return msgpack.packb(message, default=_default, use_bin_type=True)


def unpack(data: bytes) -> dict:
    """Bytes as a message (a dict), or WireError saying why not."""
    if len(data) > MAX_MESSAGE:
        raise WireError(f"message of {len(data)} bytes is over the {MAX_MESSAGE}-byte limit")
    try:
        message = msgpack.unpackb(data, raw=False, ext_hook=_ext_hook, strict_map_key=True,
                                  max_bin_len=MAX_MESSAGE, max_str_len=1 << 16)
    except WireError:
        raise
    except Exception as exc:  # noqa: BLE001 - msgpack raises several types for garbage
        raise WireError(f"not a msgpack message ({type(exc).__name__})") from None
    if not isinstance(message, dict):
        raise WireError("a message must be a map")
    return message


def request(client: str, device: str, verb: str, *args: Any) -> bytes:
    """A request as bytes."""
    return pack({"v": PROTOCOL, "client": client, "device": device, "verb": verb, "args": list(args)})


def reply_ok(value: Any = None) -> bytes:
    return pack({"ok": True, "value": value})


def reply_error(name: str, message: str) -> bytes:
    return pack({"ok": False, "error": name, "message": message})
