"""The cell's tasks: which category goes where, and the scripted teacher's poses for each."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from app.objects import fixture, semantics
from app.tasks.teacher import grasp_pose, hang_pose, shelf_pose


@dataclass(frozen=True)
class Task:
    """A pick-and-place task: grasp an object of `category`, place it on `fixture`."""

    name: str
    category: str
    fixture: str  # "rack" or "shelf"
    demo_task: str = ""  # whose demos it imitates (out-of-domain tasks borrow another's); "" = its own

    @property
    def demos(self) -> str:
        """The task directory name under demos/ whose demos this task imitates."""
        return self.demo_task or self.name

    @property
    def upright(self) -> bool:
        """Whether the place must leave the object upright (shelf tasks)."""
        return self.fixture == "shelf"

    def place_direction(self, T_base_fixture: np.ndarray) -> np.ndarray:
        """Unit direction (base frame) the object comes from onto the fixture."""
        return T_base_fixture[:3, :3] @ np.asarray(fixture(self.fixture).landmarks["approach"])


TASKS = {
    "mug": Task("mug", "mug", "rack"),  # grasp the rim, hang the handle on the peg
    "bowl": Task("bowl", "bowl", "shelf"),  # grasp the rim, put it upright on the shelf
    "bottle": Task("bottle", "bottle", "shelf"),  # grasp the neck, put it upright on the shelf
}


# Out of domain (paper Table II): demos of one category, objects of another.
OUT_OF_DOMAIN = {
    "bowl-demos-on-mug": Task("bowl-demos-on-mug", "mug", "shelf", demo_task="bowl"),
    "bottle-demos-on-vase": Task("bottle-demos-on-vase", "vase", "shelf", demo_task="bottle"),
}


def task(name: str) -> Task:
    """A task by name (in-domain or out-of-domain), or a one-line error listing the known ones."""
    known = {**TASKS, **OUT_OF_DOMAIN}
    if name not in known:
        raise ValueError(f"unknown task {name!r}; choose one of {', '.join(known)}")
    return known[name]


def teacher_grasp(mesh: trimesh.Trimesh) -> np.ndarray:
    """T_obj_tcp of the scripted teacher for a generated (scaled) instance."""
    return grasp_pose(mesh)


def teacher_place(t: Task, mesh: trimesh.Trimesh, scale: float) -> np.ndarray:
    """T_fixture_obj of the scripted teacher: the mug on the peg, bowls and bottles upright on the shelf."""
    sem = semantics(mesh)
    if t.fixture == "rack":
        return hang_pose(sem, fixture("rack"), scale)
    return shelf_pose(sem, fixture("shelf"))
