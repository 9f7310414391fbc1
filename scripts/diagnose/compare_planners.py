"""Sampling planners on the same transit problems, with the same collision checker (docs/decisions.md).

Usage (repo root): .venv/bin/python scripts/diagnose/compare_planners.py [N] [--timeout S]
N problems (default 20): a top-down TCP pose over the workspace to one above the shelf or in front
of the rack's peg, with a 6 cm pillar, 10-30 cm tall, on the table between them; only problems whose
direct joint path collides are kept. Every planner answers `PlanningScene.collisions` (the cell's
PyBullet collision model) for its states, searches the same joint box (each end +-pi) and has the
same time. Planners: OMPL's RRT-Connect (ours, `app.motion.sampling`) and pyroboplan's bidirectional
RRT-Connect, with and without its shortcutting, when pyroboplan is installed (`pip install --no-deps pyroboplan
meshcat`: its own dependencies pull drake, over 1 GB, so it is not one of ours). Prints per planner:
solved, median and p90 planning time, median path length (rad, summed over joints).
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from app.motion.sampling import SamplingConfig, densify, plan_joint_path, search_box
from app.motion.scene import PlanningScene
from hardware.robot_description import HOME_Q
from hardware.se3 import make_pose


def problems(scene: PlanningScene, n: int, seed: int = 0) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(q0, q1, pillar cloud (M, 3)) triples whose straight joint path collides and whose ends do not."""
    rng = np.random.default_rng(seed)
    kin = scene.kinematics
    down = kin.fk(HOME_Q)[:3, :3]
    out = []
    while len(out) < n:
        start = [rng.uniform(0.40, 0.62), rng.uniform(-0.12, 0.14), rng.uniform(0.10, 0.25)]
        goal = ([0.50 + rng.uniform(-0.08, 0.08), -0.45 + rng.uniform(-0.08, 0.08), rng.uniform(0.25, 0.35)]
                if rng.random() < 0.5 else [0.42 + rng.uniform(-0.05, 0.05), 0.40 + rng.uniform(-0.05, 0.05), 0.30])
        q0, q1 = kin.ik(make_pose(down, start), HOME_Q), kin.ik(make_pose(down, goal), HOME_Q)
        if q0 is None or q1 is None:
            continue
        middle = (np.array(start[:2]) + goal[:2]) / 2
        grid = np.stack(np.meshgrid(np.linspace(-0.03, 0.03, 4), np.linspace(-0.03, 0.03, 4),
                                    np.linspace(0.0, rng.uniform(0.10, 0.30), 8)), -1).reshape(-1, 3)
        pillar = grid + [*middle, 0.0]
        scene.add_cloud("pillar", pillar)
        try:
            if scene.collisions(q0) or scene.collisions(q1):
                continue
            if any(scene.collisions(q) for q in densify(np.array([q0, q1]), 0.02)):
                out.append((q0, q1, pillar))
        finally:
            scene.remove("pillar")
    return out


def ompl_rrt_connect(scene, q0, q1, timeout):
    return plan_joint_path(scene, q0, q1, config=SamplingConfig(timeout=timeout, states=10**9))  # the same time for all


def pyroboplan_rrt_connect(scene, q0, q1, timeout, shortcut: bool = True):
    """pyroboplan's RRT-Connect (and its shortcutting), its collision checks answered by our scene."""
    import pinocchio
    from pyroboplan.planning import path_shortcutting, rrt, utils

    def state_collides(model, collision_model, q, *args, **kwargs):
        return bool(scene.collisions(np.asarray(q)))

    def path_collides(model, collision_model, q_path, *args, **kwargs):
        return any(scene.collisions(np.asarray(q)) for q in q_path)

    for module in (rrt, utils, path_shortcutting):
        for name, fn in (("check_collisions_at_state", state_collides), ("check_collisions_along_path", path_collides)):
            if hasattr(module, name):
                setattr(module, name, fn)
    model = pinocchio.Model()
    for j in range(6):  # six revolute joints: pyroboplan samples within the model's limits
        model.addJoint(j, pinocchio.JointModelRZ(), pinocchio.SE3.Identity(), f"j{j}")
    model.lowerPositionLimit, model.upperPositionLimit = search_box(q0, q1, SamplingConfig().margin)  # OMPL's box
    options = rrt.RRTPlannerOptions(max_step_size=SamplingConfig().resolution, max_connection_dist=np.inf,
                                    rrt_connect=True, bidirectional_rrt=True, max_planning_time=timeout,
                                    rng_seed=1, fast_return=True)
    collision_model = pinocchio.GeometryModel()  # empty: the patched checks ask our scene instead
    path = rrt.RRTPlanner(model, collision_model, options).plan(q0, q1)
    if not path:  # None or [] when it found nothing in time
        return None
    if not shortcut:
        return np.array(path)
    return np.array(path_shortcutting.shortcut_path(model, collision_model, path,
                                                    max_step_size=SamplingConfig().resolution))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n", nargs="?", type=int, default=20)
    parser.add_argument("--timeout", type=float, default=2.0)
    args = parser.parse_args()
    scene = PlanningScene()
    cases = problems(scene, args.n)
    planners = {"ompl-rrt-connect": ompl_rrt_connect}
    try:
        import pyroboplan  # noqa: F401

        planners["pyroboplan-rrt-connect"] = pyroboplan_rrt_connect
        planners["pyroboplan-rrt-connect-unshortcut"] = lambda *a: pyroboplan_rrt_connect(*a, shortcut=False)
    except ImportError:
        print("pyroboplan is not installed: OMPL only")
    for name, plan in planners.items():
        times, lengths, solved, unsafe = [], [], 0, 0
        for q0, q1, pillar in cases:
            scene.add_cloud("pillar", pillar)
            start = time.perf_counter()
            try:
                path = plan(scene, q0, q1, args.timeout)
            except Exception as exc:  # a planner's own "no path" error
                print(f"  {name}: {type(exc).__name__}: {exc}"[:200])
                path = None
            times.append(time.perf_counter() - start)
            if path is not None:
                solved += 1
                lengths.append(float(np.abs(np.diff(path, axis=0)).sum()))
                unsafe += any(scene.collisions(q) for q in densify(path, 0.005))
            scene.remove("pillar")
        print(f"{name}: solved {solved}/{len(cases)}, colliding when checked densely {unsafe}, time median "
              f"{np.median(times):.3f} s, p90 {np.percentile(times, 90):.3f} s, path length median "
              f"{np.median(lengths) if lengths else float('nan'):.2f} rad")
    scene.close()


if __name__ == "__main__":
    main()
