"""The cell's oracle: a body of revolution's grasp turned about its axis is offered too, the place unchanged."""
import numpy as np

from app.objects import generate
from app.simcell.oracle import grasp_turns, oracle_prediction
from app.tasks.task import task
from hardware.se3 import invert, make_pose, random_rotations


def test_turns_start_with_the_teachers_own_and_go_nearest_first():
    turns = np.degrees(grasp_turns(12))
    np.testing.assert_allclose(turns, [0, 30, -30, 60, -60, 90, -90, 120, -120, 150, -150, 180])
    assert grasp_turns(1) == [0.0]


def test_turned_grasps_are_the_teachers_about_the_bottles_axis_with_one_place():
    t, mesh = task("bottle"), generate("bottle", 3)
    T_base_obj = make_pose(random_rotations(1, np.random.default_rng(0))[0], [0.5, 0.1, 0.1])
    T_base_fixture = make_pose(np.eye(3), [0.5, -0.45, 0.2])
    pred = oracle_prediction(t, mesh, 1.0, T_base_obj, T_base_fixture, turns=12)
    assert len(pred.candidates) == 12
    np.testing.assert_allclose(pred.candidates[0].T_base_tcp, pred.T_base_tcp)
    own = invert(T_base_obj) @ pred.T_base_tcp  # the teacher's grasp in the object's frame
    for c, angle in zip(pred.candidates, grasp_turns(12)):
        np.testing.assert_allclose(c.motion, pred.motion, atol=1e-12)  # the same place for every turn
        T_obj_tcp = invert(T_base_obj) @ c.T_base_tcp
        assert abs(T_obj_tcp[2, 3] - own[2, 3]) < 1e-12  # same height on the neck
        assert abs(np.linalg.norm(T_obj_tcp[:2, 3]) - np.linalg.norm(own[:2, 3])) < 1e-12  # same radius
        c_, s_ = np.cos(angle), np.sin(angle)
        Rz = np.array([[c_, -s_, 0], [s_, c_, 0], [0, 0, 1]])
        np.testing.assert_allclose(T_obj_tcp[:3, :3], Rz @ own[:3, :3], atol=1e-12)
    assert oracle_prediction(t, mesh, 1.0, T_base_obj, T_base_fixture).candidates == []
