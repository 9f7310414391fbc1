"""The shape of a request, checked before any of its fields is used: msgspec's schema validation
(types and lengths, unknown fields refused) and a depth limit, so that nothing later formats, hashes
or compares a value it did not expect (a list as a device name, a value nested 1,000 deep).

msgpack's own unpacker stops at 1,024 levels (its C stack), so unpacking itself cannot recurse
without bound; `MAX_DEPTH` keeps every later walk of a message far shallower than Python's limit.
"""
from __future__ import annotations

from typing import Annotated, Any

import msgspec

from hardware.net.wire import WireError

MAX_DEPTH = 16  # nesting levels of a request: a trajectory's rows are 3 deep
MAX_ARGS = 16
NAME = Annotated[str, msgspec.Meta(min_length=1, max_length=100)]


class Request(msgspec.Struct, forbid_unknown_fields=True, frozen=True):
    """{"v", "client", "device", "verb", "args"} of `hardware.net.wire`."""

    v: int
    client: NAME
    device: NAME
    verb: NAME
    args: Annotated[list, msgspec.Meta(max_length=MAX_ARGS)] = []


def depth(value: Any, most: int = MAX_DEPTH) -> int:
    """Nesting depth of lists and maps in a message, walked without recursion; stops counting past `most`."""
    deepest, todo = 0, [(value, 1)]
    while todo:
        item, level = todo.pop()
        if isinstance(item, (list, tuple, dict)):
            deepest = max(deepest, level)
            if deepest > most:
                return deepest
            todo.extend((v, level + 1) for v in (item.values() if isinstance(item, dict) else item))
    return deepest


def parse(message: dict) -> Request:
    """A request of the right shape, or WireError naming what is wrong (never echoing a value)."""
    if depth(message) > MAX_DEPTH:
        raise WireError(f"a request may nest at most {MAX_DEPTH} levels deep")
    try:
        return msgspec.convert(message, Request)
    except msgspec.ValidationError as exc:
        raise WireError(f"malformed request: {exc}") from None
