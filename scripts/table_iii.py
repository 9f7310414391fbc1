"""Table III (SCF order) from `nift bench --nif W --methods ibs-nif` runs, one per order:

    python scripts/table_iii.py out/table3-1 out/table3-3 out/table3-5 out/table3-7 out/table3-10

Reads each run's settings (run.json: the NIF weights), the weights' model card (order, test R^2,
training steps) and summary.json (mean overall success per pose); prints a Markdown table with
the paper's figures beside ours.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from app.bench.paper import TABLE_III
from app.nift.field import read_card


def row(run: Path) -> dict:
    """One order's figures from a bench directory."""
    settings = json.loads((run / "run.json").read_text())
    if not settings.get("nif"):
        raise ValueError(f"{run} was not run with --nif")
    card = read_card(settings["nif"])  # run.json keeps the path as given
    summary = json.loads((run / "summary.json").read_text())
    return {"order": card["architecture"]["scf_order"], "steps": card["training"]["steps"],
            "r2": card["test"]["scf_r2"], "trials": settings["trials"],
            **{pose: summary[pose]["ibs-nif"]["mean"]["overall"] for pose in summary}}


def table(runs: list[Path]) -> str:
    rows = sorted((row(r) for r in runs), key=lambda r: r["order"])
    lines = ["| SCF order | training steps | test R^2 (bands 0..n) | upright O (ours / paper) | arbitrary O (ours / paper) |",
             "|---|---|---|---|---|"]
    for r in rows:
        cells = [f"{r.get(p, float('nan')):.2f} / {TABLE_III[p][r['order']]:.2f}" for p in ("upright", "arbitrary")]
        lines.append(f"| {r['order']} | {r['steps']} | {r['r2']:.2f} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: python scripts/table_iii.py BENCH_DIR...")
    print(table([Path(a) for a in sys.argv[1:]]))
