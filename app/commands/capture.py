"""`nift capture`: spawn an unseen object in the sim cell, capture one Kinect frame, save the
object's cloud (PLY, base frame) and the colour image (PNG)."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from app.categories import POSES
from app.console.options import add_config_argument, cell_config

NAME = "capture"
HELP = "capture a single-view object cloud (PLY) and the colour image (PNG) in the sim cell"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from app.categories import CATEGORIES

    p.add_argument("--out", type=Path, default=Path("cloud.ply"), help="object cloud, PLY, base frame")
    p.add_argument("--image", type=Path, default=Path("rgb.png"), help="colour image, PNG")
    p.add_argument("--category", default="mug", choices=CATEGORIES)
    p.add_argument("--pose", default="upright", choices=POSES)
    p.add_argument("--seed", type=int, default=0, help="picks the test instance, its pose and the noise")
    p.add_argument("--calibration", type=Path, default=Path("calibration.json"),
                   help="camera calibration file; if missing, the cell is calibrated first and it is written")
    p.add_argument("--json", action="store_true", help="print what was saved as JSON")
    add_config_argument(p)


def run(args: argparse.Namespace) -> int:
    import matplotlib.image
    import numpy as np

    from app.cloud_io import save_cloud
    from app.io_utils import atomic_path
    from app.objects import split
    from app.perception import object_cloud
    from app.simcell.calibration import ensure_calibration
    from app.simcell.cell import SimCell
    from app.simcell.spawn import SCALE_RANGE, spawn

    from app.io_utils import writable_file

    if args.out.suffix.lower() != ".ply" or args.image.suffix.lower() != ".png":
        raise ValueError(f"--out {args.out} must end in .ply and --image {args.image} in .png")
    writable_file(args.out, "--out")
    writable_file(args.image, "--image")
    rng = np.random.default_rng(args.seed)
    seeds = split(args.category, "test")
    instance = int(seeds[args.seed % len(seeds)])
    with SimCell(cell_config(args)) as cell:
        T_base_cam = ensure_calibration(cell, args.calibration)
        obj = spawn(cell.world, args.category, instance, args.pose, scale=float(rng.uniform(*SCALE_RANGE)), rng=rng)
        frame = cell.camera.capture()
        cloud = object_cloud(frame, T_base_cam)
        T_obj = cell.world.pose(obj.body)
    save_cloud(args.out, cloud)
    with atomic_path(args.image) as tmp:
        matplotlib.image.imsave(tmp, frame.color, format="png")
    report = {"cloud": str(args.out), "points": len(cloud), "image": str(args.image), "category": args.category,
              "instance_seed": instance, "scale": round(obj.scale, 4), "pose": args.pose,
              "object_position": T_obj[:3, 3].round(4).tolist()}
    print(json.dumps(report, indent=2) if args.json else
          f"{args.category} {instance} ({args.pose}, scale {obj.scale:.2f}): {len(cloud)} points -> {args.out}, "
          f"colour -> {args.image}")
    return 0
