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


def defaults_toml(cls: type, header: str) -> str:
    """A TOML file for dataclass `cls` that sets nothing: `header` (comment lines), then every setting
    at its default as a commented-out line, nested dataclasses as tables - a user uncomments what they
    change (`tests/test_config_files.py` keeps the shipped files equal to this)."""
    lines = [f"# {line}".rstrip() for line in header.strip().splitlines()] + [""]
    _table(cls(), [], lines)
    return "\n".join(lines) + "\n"


def _table(obj: Any, path: list[str], lines: list[str]) -> None:
    nested = []
    if path:
        lines += ["", f"# [{'.'.join(path)}]"]
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if dataclasses.is_dataclass(value):
            nested.append((f.name, value))
        elif value is None:
            lines.append(f"# {f.name} =   (unset)")
        else:
            lines.append(f"# {f.name} = {_toml_value(value)}")
    for name, value in nested:
        _table(value, [*path, name], lines)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(int(value)) if isinstance(value, int) else repr(float(value))
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if hasattr(value, "item"):  # a numpy scalar
        return _toml_value(value.item())
    return '"' + str(value).replace("\\", "\\\\").replace('"', '\\"') + '"'
