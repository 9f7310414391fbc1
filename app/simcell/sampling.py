"""The simulated controller's state stream for a job's log: the arm's joints, TCP, the gripper's width
and the force on the tool, sampled every `every` s of simulated time from the physics loop (as a real
UR's RTDE interface streams them), while a job runs."""
from __future__ import annotations

from contextlib import contextmanager
from typing import Iterator

from app.jobs.log import JobLog
from app.simcell.cell import SimCell

EVERY = 0.02  # s of simulated time between samples (50 Hz)


@contextmanager
def sampled(cell: SimCell, job_log: JobLog, every: float = EVERY) -> Iterator[None]:
    """Hand the cell's state to `job_log` every `every` s of simulated time while the block runs (nothing
    for a log that is not active)."""
    if not job_log.active:
        yield
        return
    world = cell.world
    n = max(1, round(every / world.config.time_step))
    steps = [0]

    def sample() -> None:
        steps[0] += 1
        if steps[0] % n == 0:
            arm = cell.arm
            job_log.arm_state(arm.getActualQ(), arm.getActualTCPPose(), cell.gripper.width, cell.gripper.force,
                              arm.getActualTCPForce())

    world.on_step.append(sample)
    try:
        yield
    finally:
        world.on_step.remove(sample)
