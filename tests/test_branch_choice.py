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


def test_the_way_home_leaves_out_the_clear_line_only_where_the_direct_motion_clears_the_placed_object(cell):
    """After the retreat the arm goes straight home when that motion clears the cell and the object as it
    will stand placed (its observed hull moved from the grasp to the place); with something in the way of
    that motion it lifts clear first, as before."""
    from app.motion.planner import OBJECT, PLACED
    from hardware.se3 import invert, transform_points

    kin, planner = cell
    scene = planner.scene
    T_grasp = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.5, 0.05, 0.15])
    T_place = make_pose(rotvec_to_matrix([np.pi, 0, 0]), [0.45, -0.15, 0.15])
    box = np.stack(np.meshgrid(*[np.linspace(-0.03, 0.03, 4)] * 2, np.linspace(0.0, 0.12, 6)), -1).reshape(-1, 3)
    scene.add_cloud(OBJECT, box + [0.5, 0.05, 0.0])  # a 6 cm block the grasp holds 3 cm below its top
    try:
        q_lift = kin.ik(make_pose(T_grasp[:3, :3], T_grasp[:3, 3] + [0, 0, 0.12]), HOME_Q)
        plan = planner.place_from(q_lift, T_grasp, T_place, UP)
        assert [s.label for s in plan.segments] == ["carry", "place", "retreat", "home"]
        scene.add_cloud(PLACED, transform_points(T_place @ invert(T_grasp), scene.solids[OBJECT]))
        assert not any(scene.collisions(q, (OBJECT,)) for q in plan.segment("home").q)
        scene.remove(PLACED)
        home = plan.segment("home")
        cube = np.stack(np.meshgrid(*[np.linspace(-0.01, 0.01, 3)] * 3), -1).reshape(-1, 3)
        ends = (q_lift, plan.segment("place").q[0], plan.segment("retreat").end, HOME_Q)
        for k in np.linspace(0.2, 0.9, 15) * (len(home.q) - 1):  # a cube where the TCP passes on the way home,
            scene.add_cloud("post", cube + kin.fk(home.q[int(k)])[:3, 3])  # clear of where the arm stops
            if not any(scene.collisions(q, (OBJECT,)) for q in ends):
                break
        assert scene.collisions(home.q[int(k)], (OBJECT,)) and not any(scene.collisions(q, (OBJECT,)) for q in ends)
        blocked = planner.place_from(q_lift, T_grasp, T_place, UP)
        assert [s.label for s in blocked.segments] == ["carry", "place", "retreat", "clear", "home"]
    finally:
        for name in (OBJECT, PLACED, "post"):
            scene.remove(name)
