"""The oracle: the scripted teacher's grasp and place for an object whose mesh and pose the
simulator knows - the upper bound that checks the cell and the judges without the method."""
from __future__ import annotations

import numpy as np
import trimesh

from app.predict.methods import ORACLE
from app.predict.predict import Prediction
from app.tasks.task import Task, teacher_grasp, teacher_place
from hardware.se3 import invert


def teacher_prediction(t: Task, mesh: trimesh.Trimesh, scale: float, T_base_obj: np.ndarray,
                       T_base_fixture: np.ndarray) -> Prediction:
    """The teacher's poses as a Prediction: grasp T_base_obj @ T_obj_tcp; motion to the teacher's place."""
    goal = T_base_fixture @ teacher_place(t, mesh, scale)
    motion = goal @ invert(T_base_obj)
    return Prediction(ORACLE, T_base_obj @ teacher_grasp(mesh), invert(motion) @ T_base_fixture, motion)
