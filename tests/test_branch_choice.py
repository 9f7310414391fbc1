"""The planner's choice of IK branches and half-turns (`app.motion.planner`): by the whole job's joint
travel, start -> grasp -> place -> home, not by the nearest grasp alone."""
from __future__ import annotations

import numpy as np
import pytest

from app.failures import PlanningFailure
from app.motion import planner as planning
from app.motion.planner import HALF_TURN, FingerWidths, Planner
from app.motion.scene import PlanningScene
from hardware.interfaces import JointLimits
from hardware.kinematics import UR5Kinematics
from hardware.robot_description import HOME_Q
from hardware.se3 import make_pose, rotvec_to_matrix
from hardware.sim.arm import JOINT_ACCELERATION_LIMIT, JOINT_JERK_LIMIT

UP = np.array([0.0, 0.0, 1.0])


@pytest.fixture(scope="module")
def cell():
    kin = UR5Kinematics()
    limits = JointLimits(kin.lower, kin.upper, kin.velocity_limit, JOINT_ACCELERATION_LIMIT, JOINT_JERK_LIMIT)
    scene = PlanningScene()
    yield kin, Planner(kin, limits, scene)
    scene.close()


def every_plan(planner: Planner, monkeypatch, T_grasp: np.ndarray, T_place: np.ndarray) -> list[tuple[str, float]]:
    """(which, joint travel) of every plan the cell could run: each half-turn of the grasp, each IK branch
    at the grasp and each at the place, pinned one at a time; those that fail to plan left out."""
    solutions = planning.solutions
    pinned: dict[str, int] = {}

    def one(kin, T, q, scene=None, config=None, ignore=(), what="pose"):
        found = solutions(kin, T, q, scene, config, ignore, what)
        return [found[pinned[what]]] if pinned[what] < len(found) else []

    plans, open_fingers = [], FingerWidths.fully_open(planner.scene.geometry.stroke)
    monkeypatch.setattr(planning, "solutions", one)
    for name, flip in (("as given", np.eye(4)), ("half-turned", HALF_TURN)):
        for g in range(8):
            for p in range(8):
                pinned.update(grasp=g, place=p)
                try:
                    plan = planner._pick_place(HOME_Q, T_grasp @ flip, T_place @ flip, UP, open_fingers)
                except (PlanningFailure, IndexError):
                    continue
                plans.append((f"{name}, grasp branch {g}, place branch {p}", plan.travel))
    monkeypatch.setattr(planning, "solutions", solutions)
    return plans


def test_the_chosen_plan_travels_no_farther_than_any_other_plan_that_succeeds(cell, monkeypatch):
    """A top-down grasp in front of the arm and a place to its side, on an empty table: several IK branches
    and both half-turns plan, some of them far (the elbow or the wrist the other way round); the plan the
    planner chooses travels no farther, home included, than any of them."""
    kin, planner = cell
    down = kin.fk(HOME_Q)[:3, :3] @ rotvec_to_matrix([0.0, 0.0, 2.4])  # turned about the tool axis
    T_grasp = make_pose(down, [0.50, 0.05, 0.20])
    T_place = make_pose(down @ rotvec_to_matrix([0.0, 0.0, -1.2]), [0.35, -0.40, 0.35])
    chosen = planner.pick_place(HOME_Q, T_grasp, T_place, UP)
    others = every_plan(planner, monkeypatch, T_grasp, T_place)
    assert len(others) >= 4 and max(t for _, t in others) > chosen.travel + 3.0  # some are far
    assert chosen.travel <= min(t for _, t in others) + 1e-6, sorted(others, key=lambda o: o[1])[:3]
