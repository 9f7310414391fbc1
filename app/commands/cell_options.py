"""The options every cell verb shares: --config (a TOML CellConfig) and the seed for the camera."""
from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path


def add_config_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config", type=Path, help="cell configuration TOML (see configs/cell.toml)")


def cell_config(args: argparse.Namespace, gui: bool = False):
    """CellConfig from --config (or the defaults), with the camera seeded by --seed."""
    from app.cell import CellConfig
    from app.config import load_toml

    config = load_toml(CellConfig, args.config) if args.config else CellConfig()
    config = replace(config, camera_seed=args.seed)
    if gui:
        config = replace(config, world=replace(config.world, gui=True))
    return config
