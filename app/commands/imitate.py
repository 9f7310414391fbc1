"""`nift imitate`: grasp and place poses for a cloud, by NIFT or a baseline."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

NAME = "imitate"
HELP = "predict the grasp pose and the place motion for an object cloud from a task's demos"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from app.console.options import add_imitation_arguments
    from app.predict.methods import choices

    p.add_argument("--task", required=True, choices=["mug", "bowl", "bottle"], help="which task's demos to imitate")
    p.add_argument("--cloud", type=Path, required=True, help="object cloud in the base frame (.ply .pcd .xyz .npy)")
    p.add_argument("--method", default="nift", choices=choices(true_poses=False),
                   help="nift (= ibs-nif), a query-feature baseline, or cpd")
    p.add_argument("--demos", type=Path, help="task directory (default demos/<task>)")
    p.add_argument("--seed", type=int, default=0, help="initial rotations and translations")
    add_imitation_arguments(p)
    p.add_argument("--no-centering", "--no-center-grasp", dest="center_grasp", action="store_false",
                   help="the poses as the optimisation found them: the grasp not centred between the "
                        "fingers, a hang not centred on the peg")
    p.add_argument("--align-grasp", action="store_true",
                   help="turn the grasp so the fingers close along the normal of the wall between them (for "
                        "clouds fused from several views; docs/additions.md)")
    p.add_argument("--no-feasibility", dest="feasible", action="store_false",
                   help="the lowest-loss poses even if the fingers close on nothing or the place turns the object over")
    p.add_argument("--json", action="store_true", help="print the poses and losses as JSON")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from app.cloud_io import check_cloud, load_cloud
    from app.console.options import imitation_config

    cloud = check_cloud(load_cloud(args.cloud), str(args.cloud))
    config = imitation_config(args)  # bad input fails here, before the method's imports (torch: seconds)

    from app.predict.config import PredictConfig
    from app.predict.predict import predict
    from app.tasks.task import task
    from hardware.se3 import pose_to_ur

    settings = PredictConfig(method=args.method, demos=args.demos, imitation=config, center=args.center_grasp,
                             feasible=args.feasible, align=args.align_grasp, carried_grasps=False)
    pred = predict(task(args.task), cloud, settings)
    if args.json:
        print(json.dumps(pred.record(), indent=2))
        return 0
    np.set_printoptions(precision=4, suppress=True)
    print(f"{args.method} on {args.cloud} ({len(cloud)} points), task {args.task}")
    print(f"  grasp  T_base_tcp [x y z rx ry rz]: {np.round(pose_to_ur(pred.T_base_tcp), 4).tolist()}")
    print(f"  place  T_base_tcp [x y z rx ry rz]: {np.round(pose_to_ur(pred.T_base_tcp_place), 4).tolist()}")
    for stage, losses in pred.losses.items():
        print(f"  {stage} losses (best first): {sorted(round(v, 4) for v in losses)[:5]}  "
              f"iterations {pred.iterations.get(stage, '-')}  {pred.seconds.get(stage, '-')} s")
    return 0
