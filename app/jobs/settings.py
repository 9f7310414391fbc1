"""How a job runs: its settings (`JobConfig`), and when it looks again."""
from __future__ import annotations

from dataclasses import dataclass

from app.jobs.second_look import SecondLookConfig
from app.motion.config import MotionConfig
from app.objects import fixture
from app.perception import PerceptionConfig
from app.predict.config import PredictConfig
from app.predict.grasp_hold import HoldConfig
from app.predict.methods import method as method_record
from app.tasks.task import Task
from hardware.settings import check_integers, check_ranges


@dataclass(frozen=True)
class JobConfig:
    """How a job runs: what it predicts with (`predict`), the grip, and the settings of perception and
    motion; a job file (`configs/job.toml`, `--job-config`)."""

    predict: PredictConfig = PredictConfig()
    grasp_force: float = 40.0  # N
    approach_clearance: float = 0.04  # m the fingers open beyond the held width on the approach: no wider, so the
    # inner finger of a rim grasp stays clear of a small mug's far wall
    release_clearance: float = 0.04  # m the fingers open beyond the held width to let go: enough that an object
    # turned a few degrees in the grasp does not lean on a finger as the tool retreats; no wider, so the far
    # finger inside a bowl does not sweep its wall
    table_z: float = 0.0  # m, the table top in the base frame (the cell's layout)
    second_look: bool | None = None  # show the held object to the camera and choose the place again from what
    # it shows (app.jobs.second_look); None: on for hangs, where the held views show the handle hole, off for
    # the shelf, where imitating the place again only adds risk (docs/decisions.md)
    look: SecondLookConfig = SecondLookConfig()
    approach_contact_force: float = 30.0  # N of change of the wrist's force, held 20 ms, that stops the approach line:
    # far above what a free approach sees, far below a finger pressing on a rim
    place_contact_force: float = 30.0  # N of change, held 20 ms, that stops a predicted hang's place line and starts
    # the search beside it (app.jobs.guarded)
    leave_contact_force: float = 30.0  # N of change that stops a predicted hang's way out: the fingers met the mug
    # they let go (it swings onto the peg); they open fully and the arm carries on (app.jobs.guarded.guarded_leave)
    hold: HoldConfig = HoldConfig()  # whether a grasp will hold, judged on the cloud before the plan (app.jobs.hold)
    attempts: int = 3  # grasps tried before the job gives up
    most_plans: int = 6  # full plans tried per attempt before the plan stage gives up
    threads: int = 1  # torch threads: two threads beside one busy process took 2.5x as long as one (docs/jobs.md)
    perception: PerceptionConfig = PerceptionConfig()
    fallen_perception: PerceptionConfig = PerceptionConfig(x_range=(0.15, 0.80), y_range=(-0.26, 0.55),
                                                           z_range=(-0.03, 0.30))
    # the look for an object that fell off its fixture: the table around the fixture too, the fixtures' own points
    # left out; below the arm's elbow at home (it shows at x 0.27, z 0.35-0.40)
    motion: MotionConfig = MotionConfig()

    def __post_init__(self) -> None:
        check_integers(self, ("attempts", "most_plans", "threads"))
        check_ranges(self, RANGES)

    @property
    def method(self) -> str:
        """The method's name as configured (`predict.method`)."""
        return self.predict.method

    @classmethod
    def of(cls, method: str, **settings) -> JobConfig:
        """The default job with another method (and other job settings)."""
        return cls(predict=PredictConfig(method=method), **settings)


RANGES = (("approach_clearance", 0.0, 1.0, "m", True), ("release_clearance", 0.0, 1.0, "m", True),
          ("approach_contact_force", 0.0, 1000.0, "N", False), ("place_contact_force", 0.0, 1000.0, "N", False),
          ("leave_contact_force", 0.0, 1000.0, "N", False), ("attempts", 1, 100, "", True),
          ("most_plans", 1, 1000, "", True), ("threads", 1, 256, "", True))


def looks_again(config: JobConfig, t: Task) -> bool:
    """Whether a job of task t takes the second look: as configured, by default for a hang (a fixture
    with a peg); template methods only (not cpd, not the oracle)."""
    on = is_hang(t) if config.second_look is None else config.second_look
    return on and method_record(config.method).template


def is_hang(t: Task) -> bool:
    """Whether task t hangs its object (its fixture has a peg)."""
    return "peg_origin" in fixture(t.fixture).landmarks
