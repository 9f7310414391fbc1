"""The settings of a pick-and-place motion (`MotionConfig`): distances, speeds, tolerances, IK and the
sampling planner. No heavy imports."""
from __future__ import annotations

from dataclasses import dataclass

from app.motion.ik import IKConfig
from app.motion.sampling import SamplingConfig
from hardware.robot_description import HOME_Q
from hardware.settings import check_integers, check_ranges


@dataclass(frozen=True)
class MotionConfig:
    """Distances, speeds and tolerances of a pick-and-place motion (table `[motion]` of a job file)."""

    approach_distance: float = 0.10  # m, pre-grasp back along the tool's approach (z) axis
    shorter: tuple[float, ...] = (0.6, 0.4)  # fractions of the approach and the lift tried when a line fails
    approach_cone: float = 15.0  # degrees off the axis of the approaches tried after those
    lift_height: float = 0.12  # m, straight up after the grasp
    place_distances: tuple[float, ...] = (0.10, 0.20)  # m, pre-place back along the fixture's approach direction:
    # the first where the held object's hull is clear of the cell (the hull fills a mug's handle, which hangs on the peg)
    peg_clearance: float = 0.007  # m the object is placed above its hang on a peg, and dropped (app.motion.place_line):
    # room for a mug turned a few degrees in the grasp to pass its handle over the peg (12 mm: half the lines met it)
    peg_short: float = 0.0  # m the object is placed short of its hang, out along the peg
    retreat_distance: float = 0.10  # m, back along the tool axis after release
    carry_pivot: float = 45.0  # degrees gravity may turn about the fingers' axis on the carry (`held_without_pivot`)
    pivot_lever: float = 0.065  # m: a held object's centroid this far from the fingers' axis or farther: the planner's full
    # search for a carry that keeps it from pivoting, else a short one:
    short_lever_search: int = 1_200  # states of constrained search for an object held nearer its centroid (about 0.2 s)
    joint_speed: float = 2.0  # rad/s on transits: 63 % of the UR5's 3.15 (ur_rtde's moveJ default is 1.05)
    joint_acceleration: float = 4.0  # rad/s^2: half the base joints' 8 (docs/decisions.md, "Speeds")
    carry_speed: float = 1.05  # rad/s on the carry (the second look's turn of the wrist alone: joint_speed)
    carry_acceleration: float = 1.4  # rad/s^2 (faster, lying bottles hit the cell and stopped the arm)
    carry_wrist_speed: float = 2.0  # rad/s on the wrist's joints (4-6) carrying an object held within `pivot_lever`
    # of its centroid (a mug at its rim): the empty arm's, at a radius of a few decimetres
    carry_wrist_acceleration: float = 4.0  # rad/s^2
    line_speed: float = 0.25  # m/s on the empty gripper's straight lines: retreat, clear (ur_rtde's moveL default)
    line_acceleration: float = 1.2  # m/s^2 (ur_rtde's moveL default)
    line_jerk: float = 20.0  # m/s^3: at 5, a 10 cm line never reached its speed (0.86 s instead of 0.6)
    gentle_line_speed: float = 0.15  # m/s on the lines that end in contact or hold the object: the approach, the lift,
    # the place (faster, a bottle set down on the shelf fell over and lying bottles slipped)
    gentle_line_acceleration: float = 0.6  # m/s^2
    gentle_line_jerk: float = 5.0  # m/s^3
    blend: bool = True  # a sampled transit passes its waypoints without stopping where that stays free (app.motion.blend)
    check_step: float = 0.02  # rad: a transit is collision-checked wherever a joint has moved this far
    end_tolerance: float = 0.02  # rad: a segment that ends farther than this from its target failed
    ik_candidates: int = 8  # IK branches tried at the grasp and at the place before giving up (all of them)
    home_q: tuple[float, ...] = tuple(HOME_Q)
    ik: IKConfig = IKConfig()
    sampling: SamplingConfig = SamplingConfig()

    def __post_init__(self) -> None:
        check_integers(self, ("short_lever_search", "ik_candidates"))
        check_ranges(self, RANGES)


RANGES = (("approach_distance", 0.0, 0.5, "m", False), ("approach_cone", 0.0, 90.0, "degrees", True),
          ("lift_height", 0.0, 0.5, "m", False), ("peg_clearance", 0.0, 0.1, "m", True),
          ("peg_short", 0.0, 0.2, "m", True),
          ("retreat_distance", 0.0, 0.5, "m", False), ("carry_pivot", 0.0, 180.0, "degrees", True),
          ("pivot_lever", 0.0, 1.0, "m", True), ("short_lever_search", 1, 1_000_000, "states", True),
          ("joint_speed", 0.0, 3.15, "rad/s", False), ("joint_acceleration", 0.0, 40.0, "rad/s^2", False),
          ("line_speed", 0.0, 1.0, "m/s", False), ("line_acceleration", 0.0, 10.0, "m/s^2", False),
          ("line_jerk", 0.0, 100.0, "m/s^3", False), ("gentle_line_speed", 0.0, 1.0, "m/s", False),
          ("gentle_line_acceleration", 0.0, 10.0, "m/s^2", False), ("gentle_line_jerk", 0.0, 100.0, "m/s^3", False),
          ("check_step", 0.0, 0.5, "rad", False),
          ("carry_speed", 0.0, 3.15, "rad/s", False), ("carry_acceleration", 0.0, 40.0, "rad/s^2", False),
          ("carry_wrist_speed", 0.0, 3.2, "rad/s", False), ("carry_wrist_acceleration", 0.0, 40.0, "rad/s^2", False),
          ("end_tolerance", 0.0, 0.5, "rad", False), ("ik_candidates", 1, 8, "branches", True))
