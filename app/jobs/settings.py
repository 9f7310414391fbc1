"""How a job runs: its settings (`JobConfig`), the cell's imitation schedule, and when it looks again."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from app.jobs.second_look import SecondLookConfig
from app.motion.executor import ExecutorConfig
from app.nift.candidates import CandidateConfig
from app.nift.imitation_config import ImitationConfig
from app.objects import fixture
from app.perception import PerceptionConfig
from app.predict.methods import TEMPLATE_METHODS
from app.tasks.task import Task

# The cell's imitation schedule: prune every 10 steps down to 3 poses, one per basin, explore on 128
# points and refine on 256, leave out points of negligible weight, stop after 25 steps without gain,
# decay over 200 steps (docs/jobs.md, "Imitation time").
JOB_IMITATION = ImitationConfig(prune_every=10, explore_points=128, refine_points=256, patience=25, iterations=200,
                               keep=3, min_weight=1e-3, diverse=True, candidates=CandidateConfig(margin=0.3, most=8),
                               grasp_start_turns=2)


@dataclass(frozen=True)
class JobConfig:
    """How a job runs: the method, the grip, and the settings of perception, imitation and motion."""

    method: str = "nift"
    grasp_force: float = 40.0  # N
    approach_clearance: float = 0.04  # m the fingers open beyond the held width on the approach: fully open
    # (85 mm), the inner finger of a rim grasp landed on the far wall of a small mug (4 of 50 oracle jobs)
    release_clearance: float = 0.04  # m the fingers open beyond the held width to let go: fully open,
    # the far finger inside a bowl swept its wall on the retreat; at 2 cm a bowl that had turned 4-5
    # degrees in the grasp still leant on a finger and was dragged off the shelf
    demos: Path | None = None  # task directory (default demos/<task>)
    center_grasp: bool = True  # centre the grasp between the fingers and a hang on the peg (app.predict.grasp_centering, app.predict.peg_centering)
    align_grasp: bool = False  # turn the grasp square to the wall between the fingers (app.predict.grasp_alignment): off, as
    # one Kinect's normals at a rim are too far off (docs/additions.md, "Grasp alignment")
    feasible: bool = True  # prefer grasps that close on something and places the grasp can carry to
    # (app.predict.feasibility); what the cell can reach is chosen among the candidates (app.jobs.choice)
    carried_grasps: bool = True  # also try the demos' grasps carried from each place (app.predict.carried_grasps)
    table_z: float = 0.0  # m, the table top in the base frame (the cell's layout)
    hole_places: bool = True  # a hang also tries the places that put the handle hole seen in the cloud where
    # the demos had it, first (app.predict.hole_places); not for the oracle, whose poses are true
    second_look: bool | None = None  # show the held object to the camera and choose the place again from what
    # it shows (app.jobs.second_look); None: on for hangs, where the held views show the handle hole
    # (mug 5/20 -> 12/20), off otherwise (bowls 10/10 -> 7/10 when it imitated the place again; docs/jobs.md)
    look: SecondLookConfig = SecondLookConfig()
    approach_contact_force: float = 30.0  # N of change of the wrist's force, held 20 ms, that stops the approach line
    # (nothing held: every approach that reached its grasp changed it by 0 N; a finger on a mug's rim, 200-380 N)
    place_contact_force: float = 30.0  # N of change, held 20 ms, that stops a predicted hang's place line and starts
    # the search beside it (app.jobs.guarded)
    leave_contact_force: float = 30.0  # N of change that stops a predicted hang's way out: the fingers met the mug
    # they let go (it swings onto the peg); they open fully and the arm carries on (app.jobs.guarded.guarded_leave)
    attempts: int = 3  # grasps tried before the job gives up
    most_plans: int = 6  # full plans tried per attempt before the plan stage gives up
    threads: int = 1  # torch threads: two threads beside one busy process took 2.5x as long as one (docs/jobs.md)
    perception: PerceptionConfig = PerceptionConfig()
    fallen_perception: PerceptionConfig = PerceptionConfig(x_range=(0.15, 0.80), y_range=(-0.26, 0.55),
                                                           z_range=(-0.03, 0.30))
    # the look for an object that fell off its fixture: the table around the fixture too, the fixtures' own points
    # left out; below the arm's elbow at home (it shows at x 0.27, z 0.35-0.40)
    imitation: ImitationConfig = JOB_IMITATION
    executor: ExecutorConfig = ExecutorConfig()

    def __post_init__(self) -> None:
        for name in ("approach_clearance", "release_clearance"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"job setting {name} must be a width >= 0 in m, got {getattr(self, name)!r}")
        for name in ("approach_contact_force", "place_contact_force", "leave_contact_force"):
            if not getattr(self, name) > 0:
                raise ValueError(f"job setting {name} must be a positive force in N, got {getattr(self, name)!r}")
        for name in ("attempts", "most_plans", "threads"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 1:
                raise ValueError(f"job setting {name} must be an integer >= 1, got {getattr(self, name)!r}")


def looks_again(config: JobConfig, t: Task) -> bool:
    """Whether a job of task t takes the second look: as configured, by default for a hang (a fixture
    with a peg); template methods only (not cpd, not the oracle)."""
    on = is_hang(t) if config.second_look is None else config.second_look
    return on and config.method in TEMPLATE_METHODS


def is_hang(t: Task) -> bool:
    """Whether task t hangs its object (its fixture has a peg)."""
    return "peg_origin" in fixture(t.fixture).landmarks
