"""Pick-and-place jobs in the simulated cell: planning failures are reported and safe; jobs succeed."""
import json
from dataclasses import replace

import numpy as np
import pytest

from app.jobs import JobConfig
from app.motion.scene import PlanningScene
from app.sim.cell import CellConfig, SimCell
from app.sim.jobs import JobSpec, run_sim_job
from app.tasks.task import task


def _run(config: CellConfig, spec: JobSpec, method: str, record=None):
    with SimCell(config) as cell:
        scene = PlanningScene(config)
        try:
            T_base_cam = np.array(cell.camera.config.T_base_cam)  # calibration is tested on its own
            result = run_sim_job(cell, scene, T_base_cam, spec, JobConfig(method=method), record)
            return result, cell.arm.getActualQ(), cell.gripper.width, cell.arm.isProtectiveStopped()
        finally:
            scene.close()


def test_unreachable_place_fails_at_planning_and_leaves_the_arm_safe():
    far_shelf = replace(CellConfig(), shelf_xy_yaw=(1.6, -0.2, 0.0))  # beyond the UR5's 0.85 m reach
    result, q, width, stopped = _run(far_shelf, JobSpec(task("bottle"), seed=0), "teacher")
    assert not result.success and result.failed_stage == "plan"
    assert "place" in result.reason and "out of reach" in result.reason
    assert np.allclose(q, CellConfig().arm.home_q, atol=1e-3)  # nothing moved
    assert width > 0.08 and not stopped
    assert json.loads(json.dumps(result.record()))["failed_stage"] == "plan"


@pytest.mark.slow
@pytest.mark.parametrize("name", ["mug", "bowl", "bottle"])
def test_teacher_job_succeeds_end_to_end(name, tmp_path):
    result, q, width, stopped = _run(CellConfig(), JobSpec(task(name), seed=0), "teacher", tmp_path / "job.png")
    assert result.success, result.reason
    assert [s for s in result.seconds] == ["capture", "perceive", "imitate", "plan", "approach", "grasp", "lift",
                                           "carry", "place", "release", "retreat", "verify"]
    assert np.allclose(q, CellConfig().arm.home_q, atol=0.02) and not stopped
    assert (tmp_path / "job.png").stat().st_size > 10_000
