"""Merge `nift make-data` directories into one and cut it into parts small enough to carry to a
lent GPU machine (64 MiB a call, the repo included).

    .venv/bin/python scripts/merge_data.py OUT SRC [SRC ...] [--part-mb 40]

OUT gets every SRC's shards as hard links, renumbered, and one manifest (instances summed,
`merged_from` naming the sources); OUT-p0, OUT-p1, ... hold the same shards in parts of at most
--part-mb MB, the manifest in the last. On the GPU machine: `mkdir OUT; cp -l OUT-p*/* OUT/`.
"""
import argparse
import json
import os
from pathlib import Path

from app.training.manifest import shard_path


def merge(out: Path, sources: list[Path]) -> dict:
    """Link every source's shards into `out` under new numbers; write and return the manifest."""
    out.mkdir(parents=True, exist_ok=True)
    merged: dict | None = None
    for src in sources:
        manifest = json.loads((src / "manifest.json").read_text())
        merged = merged or {**manifest, "shards": []}
        for shard in manifest["shards"]:
            name = f"shard-{len(merged['shards']):05d}.npz"
            if not (out / name).exists():
                os.link(shard_path(src, shard["file"]), out / name)
            merged["shards"].append({**shard, "file": name})
    if merged is None:
        raise ValueError("no source directories given")
    merged["config"]["instances"] = sum(json.loads((s / "manifest.json").read_text())["config"]["instances"]
                                        for s in sources)
    merged["complete"] = all(json.loads((s / "manifest.json").read_text()).get("complete", True) for s in sources)
    merged["merged_from"] = [str(s) for s in sources]
    (out / "manifest.json").write_text(json.dumps(merged, indent=1))
    return merged


def split(out: Path, merged: dict, part_bytes: float) -> list[Path]:
    """Hard-link the shards into parts OUT-p<k> of at most `part_bytes`; the manifest goes in the last."""
    parts: list[list[str]] = [[]]
    size = 0
    for shard in merged["shards"]:
        nbytes = (out / shard["file"]).stat().st_size
        if parts[-1] and size + nbytes > part_bytes:
            parts.append([])
            size = 0
        parts[-1].append(shard["file"])
        size += nbytes
    dirs = []
    for k, files in enumerate(parts):
        d = out.parent / f"{out.name}-p{k}"
        d.mkdir(exist_ok=True)
        for f in files + (["manifest.json"] if k == len(parts) - 1 else []):
            if not (d / f).exists():
                os.link(out / f, d / f)
        dirs.append(d)
    return dirs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("sources", type=Path, nargs="+")
    ap.add_argument("--part-mb", type=float, default=40.0)
    args = ap.parse_args()
    merged = merge(args.out, args.sources)
    dirs = split(args.out, merged, args.part_mb * 1e6)
    print(f"{len(merged['shards'])} shards in {args.out}; parts: {', '.join(map(str, dirs))}")


if __name__ == "__main__":
    main()
