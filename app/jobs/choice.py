"""Choose what the cell can do: the first grasp and place pair, in the order of the template loss,
that the cell can plan (our addition; `app.predict.pairs` ranks the pairs).

Cheap tests first, the full plan last: a pair is planned only when the quick reach test
(`app.motion.ik.reach_failure`: the open gripper hits nothing and some collision-free IK exists,
~10 ms) passes at its grasp and at its place, for one of the grasp's two half-turns. Results of
the quick test are cached per pose, as many pairs share a grasp. At most `most_plans` full plans
are tried (each is 0.2-3 s); the first that succeeds is returned.

With `pick_only` (a job that looks again at what it holds before it places it), when no pair plans,
the first grasp that plans alone is returned: its place is chosen after the second look, from a
cloud that may show what the first hid (a mug's handle), so a first-look place that cannot be
reached does not stop a grasp that can.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from app.failures import NoCandidate, NoDemoLikeGrasp, PlanningFailure
from app.motion.ik import Blocked
from app.motion.planner import HALF_TURN, FingerWidths, PickPlacePlan, Planner
from app.predict.pairs import Candidate
from hardware.se3 import pose_to_ur

Failure = Callable[[np.ndarray, str], "Blocked | None"]  # TCP pose (4, 4), what it is -> why not, or None
Widths = Callable[[np.ndarray], FingerWidths]  # grasp (4, 4) -> the fingers' openings on the way

NO_DEMO_LIKE_GRASP = "no grasp like the demos'"  # how the reason of a NoDemoLikeGrasp begins
PLANNED = "planned"  # the outcome of the pair the plan stage chose
PICK_ONLY = "planned (pick only: the place waits for the second look)"
HELD = "held"  # the outcome of an attempt whose grasp held


@dataclass
class Choice:
    """The plan of the chosen pair, and what happened to every pair looked at."""

    plan: PickPlacePlan
    candidate: Candidate
    tried: list[dict] = field(default_factory=list)


def describe(c: Candidate, outcome: str) -> dict:
    """A JSON-ready line of the job record for one pair."""
    return {"score": round(c.score, 4), "grasp_rank": c.grasp_rank, "place_rank": c.place_rank,
            "grasp": np.round(pose_to_ur(c.T_base_tcp), 5).tolist(),
            "place": np.round(pose_to_ur(c.T_base_tcp_place), 5).tolist(), "outcome": outcome}


class _Cached:
    """failure(T, what), else failure(T @ half-turn, what): None when either half-turn passes; remembered per
    pose, what it is and the fingers' opening."""

    def __init__(self, failure: Failure) -> None:
        self.failure, self.seen = failure, {}

    def __call__(self, T: np.ndarray, what: str, width: float = 0.0) -> Blocked | None:
        key = (np.round(T, 6).tobytes(), what, width)
        if key not in self.seen:
            why = self.failure(T, what)
            self.seen[key] = None if why is None or self.failure(T @ HALF_TURN, what) is None else why
        return self.seen[key]


def choose(planner: Planner, candidates: list[Candidate], q_start: np.ndarray,
           place_direction: np.ndarray | Callable[[Candidate], np.ndarray],
           failure: Failure, most_plans: int = 6, widths: Widths | None = None, pick_only: bool = False) -> Choice:
    """Plan the first pair that passes the quick test at its grasp and its place and the full plan;
    NoCandidate with the best pair's reason and the count of pairs tried when none does. `place_direction`:
    the line onto the fixture, or a function of the pair giving it. `widths(T_grasp)`:
    the fingers' openings on the approach, holding and let go (fully open if not given). `pick_only`:
    when no pair plans, the first grasp that plans alone (its plan has no place)."""
    quick = _Cached(failure)
    tried: list[dict] = []
    in_table: list[bool] = []  # per pair tried: its open gripper at the grasp is in the table
    plans = 0
    for c in candidates:
        opening, why = _grasp_quick(planner, c, quick, widths)
        grasp_in_table = why is not None and why.in_table
        if not why:
            with planner.scene.fingers(opening.held):
                why = quick(c.T_base_tcp_place, "place", opening.held)
        if why:
            tried.append(describe(c, f"{why} (quick test)"))
            in_table.append(grasp_in_table)
            continue
        plans += 1
        try:
            direction = place_direction(c) if callable(place_direction) else place_direction
            plan = planner.pick_place(q_start, c.T_base_tcp, c.T_base_tcp_place, direction, opening)
        except PlanningFailure as exc:
            tried.append(describe(c, str(exc)))
            in_table.append(False)
            if plans >= most_plans:
                break
            continue
        tried.append(describe(c, PLANNED))
        return Choice(plan, c, tried)
    if pick_only and (picked := _pick_alone(planner, candidates, q_start, quick, most_plans, widths)):
        tried.append(describe(picked.candidate, PICK_ONLY))
        return Choice(picked.plan, picked.candidate, tried)
    if not tried:
        raise NoDemoLikeGrasp(f"{NO_DEMO_LIKE_GRASP} was found on this cloud (no candidate)", tried)
    if all(in_table):
        raise NoDemoLikeGrasp(f"{NO_DEMO_LIKE_GRASP} exists in this pose: every candidate's gripper "
                          f"({len(tried)}, both half-turns) would be in the table", tried)
    raise NoCandidate(f"none of {len(tried)} candidates could be planned; the best: {tried[0]['outcome']}", tried)


def _grasp_quick(planner: Planner, c: Candidate, quick: _Cached,
                 widths: Widths | None) -> tuple[FingerWidths, Blocked | None]:
    """The fingers' openings for the pair's grasp, and the quick test's reason against it (None: passes)."""
    opening = widths(c.T_base_tcp) if widths else FingerWidths.fully_open(planner.scene.geometry.stroke)
    with planner.scene.fingers(opening.approach):
        return opening, quick(c.T_base_tcp, "grasp", opening.approach)


def _pick_alone(planner: Planner, candidates: list[Candidate], q_start: np.ndarray, quick: _Cached,
                most_plans: int, widths: Widths | None) -> Choice | None:
    """The first distinct grasp (of at most `most_plans` planned) that passes the quick test and plans
    without a place; None when none does."""
    plans, seen = 0, set()
    for c in candidates:
        if c.grasp_rank in seen:
            continue
        seen.add(c.grasp_rank)
        opening, why = _grasp_quick(planner, c, quick, widths)
        if why:
            continue
        plans += 1
        try:
            return Choice(planner.pick_place(q_start, c.T_base_tcp, None, None, opening), c)
        except PlanningFailure:
            if plans >= most_plans:
                return None
    return None
