"""Why NIFT's executed mug jobs fail, per upright test mug: NIFT's grasp candidates against the
oracle's rim grasp, and its place candidates judged by the teleported place judge.

    .venv/bin/python scripts/diagnose/diagnose_nift_mug.py FIRST LAST [--fields DIR] [--calibration FILE]

For each seed it captures the cell's one Kinect view as a job does, imitates with the cell's schedule
and prints one JSON line: for the oracle's grasp and each of NIFT's first 8 grasp candidates, the TCP's
height below the cloud's top (mm) and the approach axis' angle from straight down (deg: the oracle
grasps the rim from above, near 0); and whether the best place and each of the first 8 pairs' places
would hang the mug, object teleported there (the paper's place judge; independent of the grasp).
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from app.jobs.job import JobConfig
from app.motion.scene import PlanningScene
from app.predict.config import PredictConfig
from app.predict.predict import predict
from app.simcell.calibration import ensure_calibration
from app.simcell.cell import CellConfig, SimCell
from app.simcell.sim_job import JobSpec, oracle_predictor, run_sim_job
from app.simcell.judges import judge_place, judged_copy
from app.tasks.task import task

CANDIDATES = 8


def grasp_figures(T: np.ndarray, top: float) -> list[float]:
    """[TCP height below the cloud's top (mm), approach angle from straight down (deg)]."""
    return [round(1000 * float(T[2, 3] - top), 1), round(float(np.degrees(np.arccos(np.clip(-T[2, 2], -1, 1)))), 1)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("first", type=int)
    ap.add_argument("last", type=int)
    ap.add_argument("--fields", default=None, help="other field weights: a directory of nif.pt and ndf.pt")
    ap.add_argument("--calibration", type=Path, default=Path("calibration.json"))
    args = ap.parse_args()
    t = task("mug")
    with SimCell(CellConfig()) as cell:
        T_cam = ensure_calibration(cell, args.calibration)
        scene = PlanningScene(CellConfig())
        rack, T_rack = cell.fixtures[t.fixture], cell.config.fixture_pose(t.fixture)
        for seed in range(args.first, args.last + 1):
            def predictor_of(obj, seed=seed):
                def judged(motion: np.ndarray) -> bool:
                    T = motion @ cell.world.pose(obj.body)
                    return judged_copy(cell.world, obj, T, lambda o: judge_place(cell.world, o, T, rack, False)).success

                def predictor(cloud: np.ndarray):
                    top = float(cloud[:, 2].max())
                    pred = predict(t, cloud, PredictConfig(fields=args.fields), T_rack)
                    oracle = oracle_predictor(cell, obj, t)(cloud)
                    pairs = pred.candidates[:CANDIDATES]
                    print(json.dumps({"seed": seed, "oracle_grasp": grasp_figures(oracle.T_base_tcp, top),
                                      "nift_grasps": [grasp_figures(c.T_base_tcp, top) for c in pairs],
                                      "best_place_hangs": judged(pred.motion),
                                      "pair_places_hang": [judged(c.motion) for c in pairs]}), flush=True)
                    return pred
                return predictor
            run_sim_job(cell, scene, T_cam, JobSpec(t, seed, "upright"), JobConfig(attempts=1, most_plans=1),
                        predictor_of=predictor_of)
        scene.close()


if __name__ == "__main__":
    main()
