"""Write configs/cell.toml and configs/job.toml from the settings' dataclasses: every setting at its
default, commented out (tests/test_config_files.py fails when a shipped file differs from this).
Usage (repo root): .venv/bin/python scripts/write_config_files.py"""
from pathlib import Path

from app.config import defaults_toml
from app.io_utils import atomic_path
from app.jobs.settings import JobConfig
from app.simcell.cell import CellConfig

CELL_HEADER = """The simulated cell: app.simcell.cell.CellConfig (the layout, app.layout.CellLayout; the camera), with
[world] hardware.sim.world.SimWorldConfig, [arm] hardware.sim.arm.SimArmConfig and [gripper]
hardware.sim.gripper.SimGripperConfig. Pass it with --config FILE (nift run, bench-jobs, serve, ...).
Every setting is shown at its default, commented out: uncomment what you change. Lengths in metres,
angles in radians, times in seconds, forces in newtons; an unknown key is refused by name."""
JOB_HEADER = """How a job runs: app.jobs.settings.JobConfig, with [predict] app.predict.config.PredictConfig (the
method, demos, imitation schedule and refinements), [look] app.jobs.second_look.SecondLookConfig,
[perception] and [fallen_perception] app.perception.PerceptionConfig, [motion]
app.motion.config.MotionConfig. Pass it with --job-config FILE (nift run, bench-jobs); --method and
--demos override the file. Every setting is shown at its default, commented out: uncomment what you
change. Lengths in metres, angles in radians (carry_pivot, approach_cone: degrees), forces in newtons."""
FILES = {"configs/cell.toml": (CellConfig, CELL_HEADER), "configs/job.toml": (JobConfig, JOB_HEADER)}


def main() -> None:
    for name, (cls, header) in FILES.items():
        with atomic_path(Path(name)) as tmp:
            tmp.write_text(defaults_toml(cls, header))
        print(f"wrote {name}")


if __name__ == "__main__":
    main()
