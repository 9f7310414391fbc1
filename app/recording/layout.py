"""The entity paths of a job's recording (docs/recording.md), the gripper's outline drawn at a pose,
and the blueprint the viewer opens on. Everything under `world/` is in the UR `base` frame, the frame
of every pose the job reports (`app.recording.robot.log_in_base`)."""
from __future__ import annotations

import numpy as np

from app.jobs.choice import HELD, PICK_ONLY, PLANNED
from hardware.se3 import transform_points

FIXTURES = "world/fixtures"  # /<i>: the rack, the shelf, ... as meshes
CAMERA = "world/camera"  # the camera's eye and viewing direction
IMAGES = "camera"  # /image (RGB), /depth (m): each frame the camera captured
CLOUD = "world/cloud"  # /<look>: the object's points from each look
PREDICTION = "world/prediction"  # /grasp, /place: the method's first answer
NIT = "world/nit"  # /grasp, /place: the templates' query points at the chosen pair
CANDIDATES = "world/candidates"  # /<i>: every pair looked at, coloured by outcome; its outcome (the reason) as a value
PLAN = "world/plan"  # /<segment>: the TCP's path along each planned segment
TCP = "world/tcp"  # the TCP as the arm reported it
DEMOS = "world/demos"  # /<demo>/grasp, /place: a teach-in session's saved demos
ROBOT = "robot"  # the URDF's meshes; /joints/<joint>: the joints' transforms
JOINTS = "plots/joints"  # /j1 ... /j6: joint angles (rad)
GRIPPER_WIDTH = "plots/gripper/width"  # m
GRIPPER_FORCE = "plots/gripper/force"  # N the fingers press with
TOOL_FORCE = "plots/tool/force"  # N: |F| on the tool
STAGES = "job/stages"  # a text log: each stage's start and end
VERDICT = "job/verdict"  # the outcome, and the record as JSON

GREEN, RED, BLUE, GREY = (40, 200, 80), (220, 60, 50), (60, 120, 255), (160, 160, 160)
FIXTURE_COLOUR = (150, 110, 70)


def gripper_outline(T_base_tcp: np.ndarray, opening: float = 0.085, finger: float = 0.05,
                    stem: float = 0.06) -> list[np.ndarray]:
    """Three line strips (K_i, 3) drawing a two-finger gripper at the TCP pose (4, 4): the fingers
    along the tool's y, `finger` m long ending at the TCP, and the wrist stem behind the palm along -z."""
    h = opening / 2
    strips = [np.array([[0, -h, 0], [0, -h, -finger], [0, h, -finger], [0, h, 0]]),
              np.array([[0, 0, -finger], [0, 0, -finger - stem]])]
    return [transform_points(T_base_tcp, s.astype(float)) for s in strips]


def outcome_colour(outcome: str) -> tuple[int, int, int]:
    """Green for a pair that planned or held (`app.jobs.choice`'s outcomes), red for one ruled out."""
    return GREEN if outcome in (HELD, PLANNED, PICK_ONLY) else RED


def blueprint(timeline: str = "sim"):
    """The viewer's layout: the 3-D scene beside the stage log, the camera image, and time plots of the
    joints, the gripper's width and the tool's force, on `timeline` (a job: the arm's clock)."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(name="cell", origin="/"),
            rrb.Vertical(
                rrb.TextLogView(name="stages", origin=STAGES),
                rrb.Spatial2DView(name="camera", origin=f"{IMAGES}/image"),
                rrb.TimeSeriesView(name="joints (rad)", origin=JOINTS),
                rrb.TimeSeriesView(name="gripper width (m)", origin=GRIPPER_WIDTH),
                rrb.TimeSeriesView(name="forces (N): tool, grip", contents=[TOOL_FORCE, GRIPPER_FORCE]),
                row_shares=[2, 2, 1, 1, 1],
            ),
            column_shares=[3, 2],
        ),
        rrb.TimePanel(timeline=timeline),
        collapse_panels=True,
    )
