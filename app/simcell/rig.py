"""The simulated cell's test rig as a network service (`nift serve`, kind "sim"): what the operator
and the judge do around a hardware-in-the-loop job - put an unseen object in the cell, let an
arbitrary-pose object go once it is grasped, judge where it came to rest, clear the cell,
calibrate the camera, and (for the oracle) say the object's true grasp and place. The job itself
talks only to the arm, gripper and camera services (`app.jobs.remote`)."""
from __future__ import annotations

from app.categories import POSES
from app.simcell.calibration import calibrate_sim_cell, result_record
from app.simcell.cell import SimCell
from app.simcell.sim_job import JobSpec, SimHooks, start_job, oracle_predictor
from app.simcell.spawn import release
from app.tasks.task import TASKS, task
from hardware.net import checks
from hardware.net.verbs import Service, Verb, arg


class SimRig:
    """One job at a time: `prepare` spawns its object, `verify` judges it, `clear` removes it."""

    def __init__(self, cell: SimCell) -> None:
        self.cell = cell
        self.obj = None
        self.task = None

    def prepare(self, name: str, seed: int, pose: str) -> dict:
        self.clear()
        t = task(checks.text(name, "task", tuple(TASKS)))
        spec = JobSpec(t, checks.integer(seed, "seed", 0, 2**32 - 1), checks.text(pose, "pose", POSES))
        self.obj, self.task = start_job(self.cell, spec), t
        return {"seed": seed, "pose": pose, "instance": self.obj.seed, "scale": round(self.obj.scale, 4)}

    def grasped(self) -> None:
        release(self.cell.world, self._object())

    def verify(self) -> list:
        success, reason = SimHooks(self.cell, self._object(), self.task).verify((False, ""))
        return [bool(success), reason]

    def oracle(self) -> dict:
        pred = oracle_predictor(self.cell, self._object(), self.task)(None)
        return {"T_base_tcp": pred.T_base_tcp, "T_base_fixture_seen": pred.T_base_fixture_seen, "motion": pred.motion}

    def clear(self) -> None:
        if self.obj is not None:
            self.cell.world.remove(self.obj.body)
            self.obj = None

    def calibrate(self) -> dict:
        self.clear()
        c = calibrate_sim_cell(self.cell)
        return {"T_base_cam": c.result.T_base_cam, "record": result_record(c)}

    def _object(self):
        if self.obj is None:
            raise ValueError("no object in the cell: call prepare first")
        return self.obj


def rig_service(rig: SimRig) -> Service:
    """The rig's verbs: every one steps or changes the world, so each runs on the motion thread."""
    verbs = {"prepare": Verb(lambda r, x: r.prepare(arg(x, 0), arg(x, 1), arg(x, 2, "upright")), "motion", 3),
             "grasped": Verb(lambda r, _: r.grasped(), "motion"),
             "verify": Verb(lambda r, _: r.verify(), "motion"),
             "oracle": Verb(lambda r, _: r.oracle(), "motion"),
             "clear": Verb(lambda r, _: r.clear(), "motion"),
             "calibrate": Verb(lambda r, _: r.calibrate(), "motion")}
    return Service("sim", rig, verbs, {"model": "pybullet-cell"}, moves=("arm", "gripper"))  # its verbs move them
