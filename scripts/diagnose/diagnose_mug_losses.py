"""Why NIFT's executed mug jobs fail, from one Kinect: the template losses at the oracle's poses.

For upright test mugs (seeds 0..N-1, as `nift bench-jobs` spawns them), prints
  - the grasp template's loss at the oracle's rim grasp turned to 8 azimuths about the mug's axis,
    against the loss of NIFT's best grasp (the cell's imitation schedule);
  - for 12 turns of the oracle's grasp, each carried to the rack as the medoid demo carried its mug,
    the place template's loss, and at which turn it is lowest (the demos' turn is 180 degrees).

    .venv/bin/python scripts/diagnose/diagnose_mug_losses.py [N]     (about 10 s a seed)
"""
from __future__ import annotations

import sys

import numpy as np

from app.predict.config import CELL_IMITATION
from app.nift.imitate import imitate, losses_at
from app.perception import object_cloud
from app.predict.carried_grasps import medoid
from app.predict.feasibility import demo_carries
from app.simcell.cell import CellConfig, SimCell
from app.simcell.sim_job import reset_arm, spawn_test_object, oracle_predictor
from app.tasks.demo_library import DEMOS_DIR, task_demos, task_templates
from app.tasks.task import task
from hardware.se3 import invert, make_pose, rotvec_to_matrix


def turned(T_base_obj: np.ndarray, T_base_tcp: np.ndarray, degrees: np.ndarray) -> np.ndarray:
    """(K, 4, 4) the grasp turned about the object's z axis by each angle."""
    return np.array([T_base_obj @ make_pose(rotvec_to_matrix([0.0, 0.0, np.radians(a)])) @ invert(T_base_obj)
                     @ T_base_tcp for a in degrees])


def main(seeds: int) -> None:
    t = task("mug")
    directory = DEMOS_DIR / t.demos
    templates = task_templates(t, directory)
    C = medoid(demo_carries(task_demos(directory)))
    with SimCell(CellConfig()) as cell:
        T_cam = np.array(cell.camera.config.T_base_cam)
        for seed in range(seeds):
            reset_arm(cell)
            cell.camera.reseed(np.random.SeedSequence(seed).spawn(1)[0])
            obj = spawn_test_object(cell.world, t, "upright", np.random.default_rng(seed))
            cloud = object_cloud(cell.camera.capture(), T_cam)
            oracle = oracle_predictor(cell, obj, t)(cloud)
            T_obj = cell.world.pose(obj.body)
            rim = losses_at(templates["grasp"], cloud, turned(T_obj, oracle.T_base_tcp, np.arange(0, 360, 45)),
                            CELL_IMITATION)
            best = imitate(templates["grasp"], cloud, CELL_IMITATION).candidate_losses[0]
            turns = np.arange(-180, 180, 30)
            places = turned(T_obj, oracle.T_base_tcp, turns) @ np.linalg.inv(C)
            place = losses_at(templates["place"], cloud, places, CELL_IMITATION)
            print(f"seed {seed}: grasp loss at the oracle's rim {rim.min():.1f}-{rim.max():.1f}, NIFT's best {best:.1f}; "
                  f"place loss lowest at turn {180 + turns[np.argmin(place)]} deg (the demos': 180; "
                  f"there {place[turns == 0][0]:.1f}, range {place.min():.1f}-{place.max():.1f})", flush=True)
            cell.world.remove(obj.body)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 8)
