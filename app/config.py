"""Loading configuration dataclasses from TOML files a user edits.

Each TOML table matches a dataclass field of the same name; keys that the dataclass does not have
are refused with a one-line error naming the file and the key, so a typo never goes unnoticed,
and so is a value of the wrong type for a true/false, integer, number or string setting.
"""
from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path
from typing import Any, TypeVar, get_type_hints

T = TypeVar("T")


def from_dict(cls: type[T], data: dict[str, Any], where: str = "", base: T | None = None) -> T:
    """Build dataclass `cls` from a nested dict, starting from `base` (default: its defaults); a nested
    table starts from the field's own default (a preset such as the cell's imitation schedule)."""
    base = cls() if base is None else base
    hints = get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    values = {}
    for key, value in data.items():
        if key not in names:
            raise ValueError(f"{where}unknown setting {key!r} for {cls.__name__} (known: {', '.join(sorted(names))})")
        hint = hints[key]
        if dataclasses.is_dataclass(hint):
            if not isinstance(value, dict):
                raise ValueError(f"{where}{key!r} must be a table")
            values[key] = from_dict(hint, value, where, getattr(base, key))
        elif isinstance(value, list):
            values[key] = tuple(tuple(v) if isinstance(v, list) else v for v in value)
        else:
            values[key] = _checked(hint, value, f"{where}{key!r}")
    try:
        return dataclasses.replace(base, **values)
    except ValueError as exc:  # the dataclass's own range checks
        raise ValueError(f"{where}{exc}") from None


SCALARS = {bool: "true or false", int: "an integer", float: "a number", str: "a string"}


def _checked(hint: Any, value: Any, what: str) -> Any:
    """`value` if it has the scalar type `hint` asks for (an integer is a number; a float must be
    finite); other hints pass as they are."""
    if hint not in SCALARS:
        return value
    ok = {bool: lambda v: isinstance(v, bool),
          int: lambda v: isinstance(v, int) and not isinstance(v, bool),
          float: lambda v: isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v),
          str: lambda v: isinstance(v, str)}[hint](value)
    if not ok:
        raise ValueError(f"{what} must be {SCALARS[hint]}, got {value!r}")
    return float(value) if hint is float else value


def load_toml(cls: type[T], path: str | Path, only_known: bool = False) -> T:
    """Dataclass `cls` from a TOML file, or a one-line error naming the file and the problem
    (`only_known`: leave out the top-level keys `cls` does not have - a part of a file another
    process reads whole, as `nift run --devices net` reads the layout of the served cell's file)."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such configuration file")
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML ({exc})") from exc
    if only_known:
        names = {f.name for f in dataclasses.fields(cls)}
        data = {k: v for k, v in data.items() if k in names}
    return from_dict(cls, data, where=f"{path}: ")
