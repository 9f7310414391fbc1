"""The pick-and-place planner: a grasp and a place pose to joint trajectories, with Pinocchio IK, Ruckig
and OMPL (run by `app.motion.executor`).

Plan (all of it before the arm moves, so an unreachable place fails before the pick):

    start -> pre-grasp        joint transit (Ruckig), collision-checked against table, fixtures, object hull
    pre-grasp -> grasp        straight TCP line along the tool's approach axis (dense IK); if it fails,
                              the same axis shorter, then 15 degrees off it (`approach_offsets`)
    grasp -> lift             straight line up; if it fails, shorter, then 15 degrees off vertical (`line_offsets`)
    lift -> pre-place         joint transit
    pre-place -> place        straight line along the fixture's approach direction
    place -> retreat          straight line back along the tool's approach axis (the same alternatives)
    retreat -> home           joint motion, when it clears the cell and the object as placed; else:
    retreat -> clear          straight line up
    clear -> home             joint transit

A job ends where it began, at home, so its IK branches are chosen for the whole job's joint travel:
the grasp's branches in the order of the estimated round trip start -> grasp -> place -> home
(`_round_trip`, over the place's branches), the place's in the order of carry plus way home. A
two-finger grasp turned half a turn about its approach axis is the same grasp: the turn with the
shorter round trip is planned first, the other only if it fails. A transit whose direct joint motion
would collide follows a path of OMPL's RRT-Connect (`app.motion.sampling`), passing its waypoints
without stopping where that stays free (`app.motion.blend`).
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from app.failures import NoPath, PathCollides, PlanningFailure
from app.motion.blend import blend_checked
from app.motion.carry_pivot import held_without_pivot
from app.motion.cartesian import line_path
from app.motion.config import MotionConfig
from app.motion.ik import joint_distance, solutions
from app.motion.line_offsets import approach_offsets, line_offsets
from app.motion.sampling import SamplingConfig, densify, plan_joint_path
from app.motion.scene import PlanningScene
from app.motion.trajectory import JointTrajectory, path_timing, reverse, through_waypoints
from hardware.interfaces import JointLimits
from hardware.kinematics import UR5Kinematics
from hardware.se3 import invert, line_length, make_pose, rotvec_to_matrix, transform_points

HALF_TURN = make_pose(rotvec_to_matrix([0.0, 0.0, np.pi]))
OBJECT = "object"  # the planning scene's name for the observed object's hull
PLACED = "placed"  # the same hull where the object will stand once placed (the way home clears it)
CARRY_MAY_PIVOT = "carry: no transit keeps the held object from turning about the fingers' axis"


@dataclass(frozen=True)
class FingerWidths:
    """How far apart (m) the fingers stand: on the approach and at the grasp before closing, while the
    object is held (carry, place), and once it is let go (retreat, clear, home)."""

    approach: float
    held: float
    released: float

    @classmethod
    def fully_open(cls, stroke: float) -> FingerWidths:
        return cls(stroke, stroke, stroke)


@dataclass
class PickPlacePlan:
    """The planned segments, in order, with the grasp actually used and the planning time."""

    segments: list[JointTrajectory]
    T_base_grasp: np.ndarray
    T_base_place: np.ndarray | None  # None: a pick alone, its place still to plan
    seconds: float = 0.0
    travel: float = 0.0  # rad of joint travel, summed
    carry_may_pivot: bool = False  # no carry was found that keeps the held object from turning in the fingers
    widths: FingerWidths | None = None  # the fingers' openings the plan was checked with (None: fully open)

    @property
    def notes(self) -> list[str]:
        """What the record says of the plan beyond its segments."""
        return [CARRY_MAY_PIVOT] if self.carry_may_pivot else []

    def segment(self, label: str) -> JointTrajectory:
        return next(s for s in self.segments if s.label == label)

    @property
    def duration(self) -> float:
        return float(sum(s.duration for s in self.segments))


class Planner:
    """Plans joint transits and straight lines for the cell's UR5 against a planning scene."""

    def __init__(self, kin: UR5Kinematics, limits: JointLimits, scene: PlanningScene,
                 config: MotionConfig = MotionConfig(), object_stays: bool = True) -> None:
        """`object_stays`: a placed object stays where it is let go (set down on a support), so the way home
        may be planned around it; False for one hung on a peg, which swings once let go."""
        self.kin, self.limits, self.scene, self.config = kin, limits, scene, config
        self.object_stays = object_stays

    def transit(self, q0: np.ndarray, q1: np.ndarray, label: str, ignore: tuple[str, ...] = (),
                allowed: Callable[[np.ndarray], bool] | None = None,
                search: SamplingConfig | None = None,
                profile: tuple[float | np.ndarray, float | np.ndarray] | None = None) -> JointTrajectory:
        """A collision-free chain of Ruckig joint motions q0 -> q1: the direct one, else through the
        waypoints of the sampling planner (`app.motion.sampling`); `allowed`: a path constraint on
        every state (`held_without_pivot`); `search`: the planner's settings (the configured ones when None);
        `profile`: (speed rad/s, acceleration rad/s^2; each a scalar or per joint (6,)) instead of the empty
        arm's (`_empty_profile`; a carry's: `_carry_profile`)."""
        profile = profile or self._empty_profile()
        direct = self._timed(np.array([q0, q1]), label, profile=profile)
        hits = self._collisions(direct, ignore, allowed)
        if not hits:
            return direct
        try:
            waypoints = plan_joint_path(self.scene, q0, q1, ignore, search or self.config.sampling, allowed)
        except NoPath as exc:
            raise NoPath(f"{label}: {exc} (the direct one hits {', '.join(hits[:3])})") from None
        if self.config.blend:  # through the waypoints without a stop at each (app.motion.blend)
            traj = self._blended(waypoints, label, profile, ignore, allowed)
            if not self._collisions(traj, ignore, allowed):
                return traj
        dense = densify(waypoints, self.config.sampling.max_step / 2)
        # last, on the very segments the planner checked (docs/decisions.md)
        for path, straight in ((waypoints, False), (dense, False), (waypoints, True)):
            traj = self._timed(path, label, straight, profile)
            if not self._collisions(traj, ignore, allowed):
                return traj
        raise PathCollides(f"{label}: the sampled joint path collides once timed ({', '.join(hits[:3])} on the direct one)")

    def carry(self, q0: np.ndarray, q1: np.ndarray, ignore: tuple[str, ...] = (),
              lever: float = 0.0) -> tuple[JointTrajectory, bool]:
        """The transit with the object held, and whether it keeps the object from pivoting: one that
        turns it little about the fingers' axis first (`held_without_pivot`), else any. A joint transit
        between IK branches swung a bottle held 11 cm above its centroid (`lever`) upside down, and it
        turned 81 degrees in the grasp; such a carry gets the planner's full search and, failing, says
        so. A mug held at its rim (4-5 cm) mostly rides such swings (1-4 degrees), once turned 24: its
        search is short (`short_lever_search`) and any transit is taken without a word."""
        short = lever < self.config.pivot_lever
        search = replace(self.config.sampling, states=self.config.short_lever_search) if short else None
        profile = self._carry_profile(short)
        try:
            return self.transit(q0, q1, "carry", ignore, held_without_pivot(self.kin, q0, q1, self.config.carry_pivot),
                                search, profile=profile), True
        except PlanningFailure:
            return self.transit(q0, q1, "carry", ignore, profile=profile), short

    def _carry_profile(self, short: bool) -> tuple[np.ndarray, np.ndarray]:
        """(speeds rad/s, accelerations rad/s^2) (6,) of a carry: the carry's on every joint, the wrist's
        three (4-6) at `carry_wrist_*` for an object held near its centroid (`short`: its lever under
        `pivot_lever`), which they swing about a short radius (docs/decisions.md, "Speeds")."""
        c = self.config
        speed, acceleration = np.full(6, c.carry_speed), np.full(6, c.carry_acceleration)
        if short:
            speed[3:], acceleration[3:] = c.carry_wrist_speed, c.carry_wrist_acceleration
        return speed, acceleration

    def held_lever(self, T_base_grasp: np.ndarray) -> float:
        """How far (m) the observed object's centroid lies from the fingers' axis (the tool's y through
        the TCP) when grasped at T_base_grasp: the arm gravity turns it about; 0 without a cloud."""
        solid = self.scene.solids.get(OBJECT)
        if solid is None:
            return 0.0
        r = transform_points(invert(T_base_grasp), solid.mean(axis=0, keepdims=True))[0]  # (3,) TCP frame
        return float(np.hypot(r[0], r[2]))

    def _empty_profile(self) -> tuple[float, float]:
        """(speed rad/s, acceleration rad/s^2) of a transit with nothing held."""
        return self.config.joint_speed, self.config.joint_acceleration

    def _blended(self, waypoints: np.ndarray, label: str, profile: tuple[float, float], ignore: tuple[str, ...],
                 allowed: Callable[[np.ndarray], bool] | None) -> JointTrajectory:
        """The sampled path's waypoints passed without stopping where the blend stays free (`blend_checked`)."""
        def first_bad(traj: JointTrajectory) -> float | None:
            hit = self._first_hit(traj, ignore, allowed, limits=True)
            return None if hit is None else float(traj.times[hit[0]])

        return blend_checked(waypoints, self.limits, *profile, label, first_bad)

    def _timed(self, waypoints: np.ndarray, label: str, straight: bool = False,
               profile: tuple[float, float] | None = None) -> JointTrajectory:
        """Ruckig rest-to-rest segments through joint waypoints (K, 6); `straight`: each on its straight segment;
        `profile`: (speed, acceleration), the empty arm's transit when None."""
        return through_waypoints(list(waypoints), self.limits, *(profile or self._empty_profile()), label, straight)

    def line(self, q0: np.ndarray, T1: np.ndarray, label: str, ignore: tuple[str, ...] = (),
             gentle: bool = False) -> JointTrajectory:
        """A straight TCP line from FK(q0) to T1, timed under the joint limits; `gentle`: a line that ends
        in contact or holds the object (the approach, the lift, the place) runs at the `gentle_line_*`
        profile."""
        T0 = self.kin.fk(q0)
        path = line_path(self.kin, T0, T1, q0, self.scene, ignore, label)
        c = self.config
        if gentle:
            profile = (c.gentle_line_speed, c.gentle_line_acceleration, c.gentle_line_jerk)
        else:
            profile = (c.line_speed, c.line_acceleration, c.line_jerk)
        return path_timing(path, line_length(T0, T1), self.limits, *profile, label)

    def pick_place(self, q_start: np.ndarray, T_base_grasp: np.ndarray, T_base_place: np.ndarray | None,
                   place_direction: np.ndarray | None, widths: FingerWidths | None = None) -> PickPlacePlan:
        """The whole motion for a grasp and a place pose of the TCP; `place_direction` (3,) is the
        unit direction the object comes from onto the fixture (base frame); `widths`: the fingers'
        openings on the way (fully open when not given). T_base_place None: the pick alone (to the
        pre-grasp, approach, lift), its place planned later with `place_from`."""
        start = time.perf_counter()
        widths = widths or FingerWidths.fully_open(self.scene.geometry.stroke)
        errors: list[PlanningFailure] = []
        plans = []  # a plan whose carry may pivot the object is kept while the other half-turn is tried
        for flip in self._flips_shortest_first(q_start, T_base_grasp, T_base_place):
            try:
                T_place = None if T_base_place is None else T_base_place @ flip
                plans.append(self._pick_place(q_start, T_base_grasp @ flip, T_place, place_direction, widths))
            except PlanningFailure as exc:
                errors.append(exc)
                continue
            if not plans[-1].carry_may_pivot:
                break
        if plans:
            plan = next((p for p in plans if not p.carry_may_pivot), plans[0])
            plan.seconds = time.perf_counter() - start
            return plan
        raise type(errors[0])(" / ".join(dict.fromkeys(str(e) for e in errors)))  # the first half-turn's kind

    def _flips_shortest_first(self, q_start: np.ndarray, T_base_grasp: np.ndarray,
                             T_base_place: np.ndarray | None = None) -> list[np.ndarray]:
        """The grasp and its half-turn, the one with the shortest job first (`_round_trip` over its IK
        branches; without a place, the branch nearest q_start): the other is planned only if the first cannot be."""
        def cost(flip: np.ndarray) -> float:
            branches = self.kin.ik_all(T_base_grasp @ flip, q_start)
            if T_base_place is None:
                return min((joint_distance(q, q_start, self.config.ik.joint_weights) for q in branches), default=np.inf)
            return min((self._round_trip(q_start, q, T_base_place @ flip) for q in branches), default=np.inf)

        return sorted((np.eye(4), HALF_TURN), key=cost)

    def _pick_place(self, q_start, T_grasp, T_place, place_direction, widths) -> PickPlacePlan:
        c = self.config
        lifts = [make_pose(T_grasp[:3, :3], T_grasp[:3, 3] + up) for up in line_offsets(np.array([0.0, 0.0, 1.0]),
                                                                                          c.lift_height, c)]

        approaches = [T_grasp @ make_pose(t=offset) for offset in approach_offsets(c)]

        def grasp_lines(q: np.ndarray):
            with self.scene.fingers(widths.held):
                lift = self._first_line(q, lifts, "lift", gentle=True)  # shorter lifts: the carry that follows is checked
            if T_place is not None:
                with self.scene.holding(OBJECT, T_grasp), self.scene.fingers(widths.held):
                    if hits := self.scene.collisions(lift.end, (OBJECT,)):  # the carry would start in collision:
                        raise PathCollides(f"lift: the held object meets the arm at its end ({', '.join(hits[:3])})")
            with self.scene.fingers(widths.approach):
                return reverse(self._first_line(q, approaches, "approach", gentle=True)), lift

        # IK at the ends of the lines first: they decide the configuration each line runs in
        with self.scene.fingers(widths.approach):
            at_grasp = solutions(self.kin, T_grasp, q_start, self.scene, c.ik, (OBJECT,), "grasp")
        if T_place is not None:
            at_grasp.sort(key=lambda q: self._round_trip(q_start, q, T_place))
        approach, lift = self._first(at_grasp, grasp_lines)
        with self.scene.fingers(widths.approach):
            to_pre_grasp = self.transit(q_start, approach.q[0], "to pre-grasp")
        rest, pivot = ([], False) if T_place is None else self._place_segments(lift.end, T_grasp, T_place,
                                                                             place_direction, widths)
        segments = [to_pre_grasp, approach, lift, *rest]
        travel = float(sum(np.abs(np.diff(s.q, axis=0)).sum() for s in segments))
        return PickPlacePlan(segments, T_grasp, T_place, travel=travel, carry_may_pivot=pivot, widths=widths)

    def _round_trip(self, q_start: np.ndarray, q_grasp: np.ndarray, T_place: np.ndarray) -> float:
        """The joint travel (rad, summed over the joints) of a job through the grasp's IK branch q_grasp: from
        q_start to it, on to the place's branch that makes the rest shortest, and home - an estimate, the
        transits taken as straight and the lines left out."""
        rest = [self._onward(q_grasp, q) for q in self.kin.ik_all(T_place, q_grasp)]
        return travel(q_start, q_grasp) + min(rest, default=0.0)

    def _onward(self, q_from: np.ndarray, q_place: np.ndarray) -> float:
        """The joint travel (rad) from q_from to the place's branch q_place and from there home, as straight motions."""
        return travel(q_from, q_place) + travel(q_place, np.asarray(self.config.home_q))

    def place_from(self, q_now: np.ndarray, T_base_grasp: np.ndarray, T_base_place: np.ndarray,
                   place_direction: np.ndarray, widths: FingerWidths | None = None) -> PickPlacePlan:
        """The rest of a job from q_now with the object held as grasped at T_base_grasp (no half-turn:
        the grasp is made): carry, place, retreat, clear, home (`pick_place` for the arguments)."""
        start = time.perf_counter()
        widths = widths or FingerWidths.fully_open(self.scene.geometry.stroke)
        segments, pivot = self._place_segments(q_now, T_base_grasp, T_base_place, place_direction, widths)
        travel = float(sum(np.abs(np.diff(s.q, axis=0)).sum() for s in segments))
        return PickPlacePlan(segments, T_base_grasp, T_base_place, time.perf_counter() - start, travel, pivot, widths)

    def _place_segments(self, q_from, T_grasp, T_place, place_direction,
                        widths: FingerWidths) -> tuple[list[JointTrajectory], bool]:
        """carry (from q_from, the object held), place, retreat, clear, home; and whether the carry may
        pivot the held object."""
        c = self.config
        held, released = widths.held, widths.released

        def place_lines(q: np.ndarray, T_pre_place: np.ndarray):
            with self.scene.fingers(held):
                place = reverse(self.line(q, T_pre_place, "place", (OBJECT,), gentle=True))
            with self.scene.fingers(released):  # a retreat that leaves no way up is no retreat
                return place, *self._retreat_and_clear(q, T_place)

        with self.scene.fingers(held):
            at_place = solutions(self.kin, T_place, q_from, self.scene, c.ik, (OBJECT,), "place")
        at_place.sort(key=lambda q: self._onward(q_from, q))  # the carry and the way home, shortest first
        for distance in c.place_distances:  # farther out when the held hull meets the fixture at the pre-place
            T_pre_place = make_pose(T_place[:3, :3], T_place[:3, 3] + distance * np.asarray(place_direction))
            place, retreat, clear = self._first(at_place, lambda q: place_lines(q, T_pre_place))
            with self.scene.holding(OBJECT, T_grasp), self.scene.fingers(held):
                if not self.scene.collisions(place.q[0], (OBJECT,)):
                    break
        with self.scene.holding(OBJECT, T_grasp), self.scene.fingers(held):  # the carried object must clear the cell too
            carry, kept = self.carry(q_from, place.q[0], (OBJECT,), self.held_lever(T_grasp))
        with self.scene.fingers(released):
            return [carry, place, *self._way_home(retreat, clear, T_grasp, T_place)], not kept

    def _way_home(self, retreat: JointTrajectory, clear: JointTrajectory, T_grasp: np.ndarray | None,
                  T_place: np.ndarray) -> list[JointTrajectory]:
        """retreat, then straight home where that clears the object placed at T_place (`_straight_home`),
        else clear and the transit home (the fingers as they are set)."""
        if T_grasp is not None and (direct := self._straight_home(retreat.end, T_grasp, T_place)):
            return [retreat, direct]
        return [retreat, clear, self.transit(clear.end, np.asarray(self.config.home_q), "home", ignore=(OBJECT,))]

    def _straight_home(self, q: np.ndarray, T_grasp: np.ndarray, T_place: np.ndarray) -> JointTrajectory | None:
        """The direct joint motion home from the retreat's end at q, when it clears the cell and the object
        as it will stand placed (the observed object's hull moved from the grasp to the place): the clear
        line up is then left out. None when it does not, without an observed object (nothing to clear), or
        for an object that does not stay where it is let go (`object_stays`)."""
        solid = self.scene.solids.get(OBJECT)
        if solid is None or not self.object_stays:
            return None
        self.scene.add_cloud(PLACED, transform_points(T_place @ invert(T_grasp), solid))
        try:
            home = self._timed(np.array([q, self.config.home_q]), "home")
            return None if self._collisions(home, (OBJECT,)) else home
        finally:
            self.scene.remove(PLACED)

    def _retreat_and_clear(self, q: np.ndarray, T_place: np.ndarray,
                           touching: tuple[str, ...] = ()) -> tuple[JointTrajectory, JointTrajectory]:
        """From a place at q (the TCP at T_place): the first retreat back along the tool's axis (or one
        of its alternatives) from whose end a line straight up works too, and that line; `touching`:
        obstacles the retreat itself may start on."""
        c = self.config
        backs = line_offsets(np.array([0.0, 0.0, -1.0]), c.retreat_distance, c)  # in the TCP frame at the place

        def retreat_and_clear(T_retreat: np.ndarray):
            retreat = self.line(q, T_retreat, "retreat", (OBJECT, *touching))
            T_clear = self.kin.fk(retreat.end)
            T_clear[2, 3] += c.lift_height
            return retreat, self.line(retreat.end, T_clear, "clear", (OBJECT,))

        return first_that_works([T_place @ make_pose(t=back) for back in backs], retreat_and_clear)

    def leave(self, q: np.ndarray, released: float, fixture: str, T_grasp: np.ndarray | None = None) -> list[JointTrajectory]:
        """retreat, clear, home from where the object was let go at q (the fingers `released` m apart),
        planned there and then: a place line that a contact cut short ends off its planned place, the
        fingers maybe on the `fixture` it met (then the retreat may start on it: mug 31's finger was
        within the scene's margin of the rack). With the grasp `T_grasp` the object was held at, the
        retreat goes straight home where that clears the object let go here (`_straight_home`)."""
        T = self.kin.fk(q)
        with self.scene.fingers(released):
            try:
                retreat, clear = self._retreat_and_clear(q, T)
            except PlanningFailure:
                retreat, clear = self._retreat_and_clear(q, T, touching=(fixture,))
            return self._way_home(retreat, clear, T_grasp, T)

    def _first_line(self, q: np.ndarray, targets: list[np.ndarray], label: str,
                    gentle: bool = False) -> JointTrajectory:
        """The line from FK(q) to the first target it can follow (the default first, then the alternatives)."""
        return first_that_works(targets, lambda T: self.line(q, T, label, (OBJECT,), gentle))

    def _first(self, candidates: list[np.ndarray], plan_lines):
        """plan_lines(q) for the first IK candidate (of at most `ik_candidates`) whose lines work."""
        return first_that_works(candidates[: self.config.ik_candidates], plan_lines)

    def _collisions(self, traj: JointTrajectory, ignore: tuple[str, ...],
                    allowed: Callable[[np.ndarray], bool] | None = None) -> list[str]:
        """What the timed motion hits (or 'path constraint' where `allowed` refuses a state); [] if nothing."""
        hit = self._first_hit(traj, ignore, allowed)
        return [] if hit is None else hit[1]

    def _first_hit(self, traj: JointTrajectory, ignore: tuple[str, ...],
                   allowed: Callable[[np.ndarray], bool] | None = None,
                   limits: bool = False) -> tuple[int, list[str]] | None:
        """The first checked sample (`checked_indices`, and the end) where the timed motion fails, and what
        it hits there ('path constraint' where `allowed` refuses it; 'joint limits' outside them, when
        `limits`); None when it fails nowhere."""
        for k in [*checked_indices(traj.q, self.config.check_step), len(traj.q) - 1]:
            q = traj.q[k]
            if limits and not self.limits.contains(q):
                return k, ["joint limits"]
            if hits := self.scene.collisions(q, ignore):
                return k, hits
            if allowed is not None and not allowed(q):
                return k, ["path constraint"]
        return None


def travel(q0: np.ndarray, q1: np.ndarray) -> float:
    """Joint travel (rad) of a straight joint motion: the joints' distances summed."""
    return float(np.abs(np.asarray(q1) - np.asarray(q0)).sum())


def checked_indices(q: np.ndarray, step: float) -> list[int]:
    """Which samples of a joint path (K, 6) to collision-check: the first, each that has moved more than
    `step` rad on some joint since the last one kept - as dense at any speed."""
    kept, last = [0], q[0]
    for i in range(1, len(q)):
        if np.abs(q[i] - last).max() > step:
            kept.append(i)
            last = q[i]
    return kept


def first_that_works(items: list, attempt):
    """attempt(item) for the first item it succeeds on; the first item's PlanningFailure if none does."""
    errors: list[PlanningFailure] = []
    for item in items:
        try:
            return attempt(item)
        except PlanningFailure as exc:
            errors.append(exc)
    raise errors[0]
