"""How a cloud becomes grasp and place poses (`PredictConfig`): the method, the demos, the imitation
schedule and our refinements, with one default each - the cell's. No heavy imports."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from app.nift.candidates import CandidateConfig
from app.nift.imitation_config import ImitationConfig
from app.predict.methods import method as method_record

# The cell's imitation schedule: prune every 10 steps down to 3 poses, one per basin, explore on 128
# points and refine on 256, leave out points of negligible weight, stop after 25 steps without gain,
# decay over 200 steps, and start grasps from the demos' too (docs/journal/jobs-2026-11-to-12-05.md).
# `ImitationConfig()` alone is the teleported benchmark's schedule (docs/benchmark.md).
CELL_IMITATION = ImitationConfig(prune_every=10, explore_points=128, refine_points=256, patience=25, iterations=200,
                                 keep=3, min_weight=1e-3, diverse=True, candidates=CandidateConfig(margin=0.3, most=8),
                                 grasp_start_turns=2)


@dataclass(frozen=True)
class PredictConfig:
    """What `app.predict.predict.predict` does with a cloud (table `[predict]` of a job file)."""

    method: str = "nift"  # a name or alias of `app.predict.methods`
    demos: Path | None = None  # the task's demo directory (default demos/<task>)
    fields: Path | None = None  # other field weights: a NIF .pt, or a directory of nif.pt and ndf.pt (default: shipped)
    imitation: ImitationConfig = CELL_IMITATION
    center: bool = True  # centre the grasp between the fingers and a hang on the peg (grasp_centering, peg_centering)
    align: bool = False  # turn the grasp square to the wall between the fingers (grasp_alignment): off, as one
    # Kinect's normals at a rim are too far off (docs/additions.md, "Grasp alignment")
    feasible: bool = True  # prefer grasps that close on something and places the grasp can carry to (feasibility)
    carried_grasps: bool = True  # also pair each place with the demos' grasps carried from it (carried_grasps)
    hole_places: bool = True  # a hang also tries the places that put the handle hole seen in the cloud where the
    # demos had it, first (hole_places); never for a method that reads true poses

    def __post_init__(self) -> None:
        method_record(self.method)  # an unknown method is refused by name
        for name in ("demos", "fields"):
            value = getattr(self, name)
            if value is not None and not isinstance(value, Path):
                object.__setattr__(self, name, Path(value))  # TOML gives a string
