"""The oracle: the scripted teacher's grasp and place for an object whose mesh and pose the
simulator knows - the upper bound that checks the cell and the judges without the method."""
from __future__ import annotations

import numpy as np
import trimesh

from app.categories import REVOLUTION
from app.predict.pairs import Candidate
from app.predict.methods import ORACLE
from app.predict.predict import Prediction
from app.tasks.task import Task, teacher_grasp, teacher_place
from hardware.se3 import invert, make_pose, rotvec_to_matrix

TURNS = 12  # such turns of the teacher's grasp (30 degrees apart) the cell's oracle offers


def grasp_turns(turns: int) -> list[float]:
    """Angles (rad) about the object's axis, the teacher's own (0) first, then nearest first: 0, +a, -a, +2a, ..."""
    step = 2 * np.pi / turns
    return [0.0] + [sign * k * step for k in range(1, turns // 2 + 1) for sign in (1, -1)][: turns - 1]


def oracle_prediction(t: Task, mesh: trimesh.Trimesh, scale: float, T_base_obj: np.ndarray,
                       T_base_fixture: np.ndarray, turns: int = 1) -> Prediction:
    """The teacher's poses as a Prediction: grasp T_base_obj @ T_obj_tcp; motion to the teacher's place.
    `turns` > 1 (bodies of revolution only): the same grasp turned about the object's axis are
    candidates too, the teacher's first - an object lying on the table is often graspable only at
    another point of its rim or neck (the place, an object pose, is the same for all)."""
    goal = T_base_fixture @ teacher_place(t, mesh, scale)
    motion = goal @ invert(T_base_obj)
    seen = invert(motion) @ T_base_fixture
    grasps = [T_base_obj @ make_pose(rotvec_to_matrix([0.0, 0.0, a])) @ teacher_grasp(mesh) for a in grasp_turns(turns)]
    candidates = [Candidate(G, seen, T_base_fixture, grasp_rank=k) for k, G in enumerate(grasps)] if turns > 1 else []
    return Prediction(ORACLE, grasps[0], seen, motion, candidates=candidates)
