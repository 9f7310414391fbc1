"""Printing results the same way in every verb: a two-column table, or JSON with --json."""
from __future__ import annotations

import json


def _shown(value) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, list):
        return "[" + ", ".join(_shown(v) for v in value) + "]"
    return str(value)


def print_figures(figures: dict, as_json: bool, targets: dict[str, str] | None = None) -> None:
    """Print a flat dict of figures; `targets` adds a '(target ...)' note after named rows."""
    if as_json:
        print(json.dumps(figures, indent=2))
        return
    targets = targets or {}
    width = max(len(k) for k in figures) + 2
    for key, value in figures.items():
        note = f"   (target {targets[key]})" if key in targets else ""
        print(f"{key:<{width}}{_shown(value)}{note}")
