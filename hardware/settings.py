"""Range checks for device settings (our addition): a negative time step or force limit is refused
when the settings are made, in one line naming the setting, instead of failing later with a
misleading reason (dataclass fields; no import of the application)."""
from __future__ import annotations

import math
from typing import Any

Range = tuple[str, float, float, str, bool]  # name, low, high, unit, low included


def check_ranges(settings: Any, ranges: tuple[Range, ...]) -> None:
    """ValueError naming the first field of `settings` outside its range."""
    for name, low, high, unit, closed in ranges:
        value = getattr(settings, name)
        above = value >= low if closed else value > low
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and above
                                                                                  and value <= high):
            bracket = "[" if closed else "("
            raise ValueError(f"{name} must be in {bracket}{low:g}, {high:g}] {unit}, got {value!r}")
