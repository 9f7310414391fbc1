"""Checks for settings dataclasses, the one validation style of every setting (devices, jobs, the
method): a value out of range, of the wrong kind or not among its choices is refused when the
settings are made, in one line naming the setting, instead of failing later with a misleading
reason. Plain Python (no import of the application), so every floor may use it."""
from __future__ import annotations

import math
from typing import Any

Range = tuple[str, float, float, str, bool]  # name, low, high, unit, low included


def check_integers(settings: Any, names: tuple[str, ...]) -> None:
    """ValueError naming the first of `names` whose value is not an integer (True is not one)."""
    for name in names:
        value = getattr(settings, name)
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{name} must be an integer, got {value!r}")


def check_choices(settings: Any, choices: dict[str, tuple[str, ...]]) -> None:
    """ValueError naming the first setting whose value is not one of its choices."""
    for name, allowed in choices.items():
        if getattr(settings, name) not in allowed:
            raise ValueError(f"unknown {name} {getattr(settings, name)!r}; choose one of {', '.join(allowed)}")


def check_ranges(settings: Any, ranges: tuple[Range, ...]) -> None:
    """ValueError naming the first field of `settings` outside its range."""
    for name, low, high, unit, closed in ranges:
        value = getattr(settings, name)
        above = value >= low if closed else value > low
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and above
                                                                                  and value <= high):
            bracket, unit_ = "[" if closed else "(", f" {unit}" if unit else ""
            raise ValueError(f"{name} must be in {bracket}{low:g}, {high:g}]{unit_}, got {value!r}")
