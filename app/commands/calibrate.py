"""`nift calibrate`: eye-to-hand calibration of the Kinect on the sim cell -> a calibration file."""
from __future__ import annotations

import argparse
from pathlib import Path

from app.console.options import add_config_argument, cell_config
from app.console.output import print_figures

NAME = "calibrate"
HELP = "eye-to-hand calibrate the camera with a ChArUco board on the flange; write the calibration file"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", type=Path, default=Path("calibration.json"), help="calibration file to write")
    p.add_argument("--views", type=int, default=20, help="arm poses to visit (15-30 is usual)")
    p.add_argument("--seed", type=int, default=0, help="draws the poses")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    add_config_argument(p)


def run(args: argparse.Namespace) -> int:
    from app.simcell.calibration import calibrate_sim_cell, result_record
    from app.simcell.cell import SimCell
    from calibration.store import save_calibration

    from app.io_utils import writable_file

    if args.views < 3:
        raise ValueError(f"--views must be at least 3, got {args.views}")
    writable_file(args.out, "--out")
    cell_cfg = cell_config(args)
    with SimCell(cell_cfg) as cell:
        calibration = calibrate_sim_cell(cell, views=args.views, seed=args.seed)
    record = result_record(calibration)
    save_calibration(args.out, calibration.result.T_base_cam, record)
    figures = {k: v for k, v in record.items() if k != "T_tcp_board"}
    print_figures({"file": str(args.out), **figures}, args.json)
    return 0
