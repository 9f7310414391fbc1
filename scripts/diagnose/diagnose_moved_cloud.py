"""How many optimiser initialisations it takes to find a demo's grasp again on its own cloud moved rigidly.

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_moved_cloud.py
The setting of tests/test_imitation.py (a train mug, 10 random rigid moves); prints successes
(within 1 cm / 10 degrees) and seconds for 10 and 20 pruned inits and the paper's schedule.
"""
import sys
import time

import numpy as np

sys.path.insert(0, "tests")  # the test's scene, so the figures are the test's
from test_imitation import demo_scene, errors  # noqa: E402

from app.nift.imitate import ImitationConfig, imitate  # noqa: E402
from app.nift.template import build_template  # noqa: E402
from app.tasks.anchors import anchor_mesh
from hardware.se3 import make_pose, random_rotations

cloud, T_grasp, _ = demo_scene()
template = build_template("gripper", anchor_mesh("gripper"), [{"cloud": cloud, "T_frame_anchor": T_grasp}])
for name, options in [("10 inits, pruned", dict(inits=10)), ("20 inits, pruned", dict(inits=20)),
                      ("the paper's: 10 inits, no pruning", dict(inits=10, prune_every=0))]:
    rng, good, start = np.random.default_rng(5), 0, time.perf_counter()
    for R in random_rotations(10, rng):
        M = make_pose(R, rng.uniform(-0.1, 0.1, 3))
        found = imitate(template, cloud @ M[:3, :3].T + M[:3, 3], ImitationConfig(seed=2, **options)).T
        dist, angle = errors(found, M @ T_grasp)
        good += dist <= 0.01 and angle <= 10.0
    print(f"{name}: {good}/10 within 1 cm / 10 deg, {(time.perf_counter() - start) / 10:.1f} s each", flush=True)
