"""Grasps that will hold, and away from one that slipped (our addition; the judgement is
`app.predict.grasp_hold`).

Before the plan, each candidate's grasp is judged on the cloud the camera saw. A grasp that would
slide out is tried again moved down its pad plane by `HoldConfig.moves` (off a cap that narrows to
the top, onto the neck or the body); when no move holds, it is ruled out and the record says why.
After a slip, grasps within `HoldConfig.slip_away` of the slipped one are ruled out too. Positions on
the object are compared in the cloud's principal-axis frame - the position along the longest axis, of
either sign, and the distance from it - so the object may have fallen, turned about its axis, or
flipped end over end since.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from app.jobs.choice import describe
from app.predict.grasp_hold import Hold, HoldConfig, judge_hold, moved_down
from app.predict.pairs import Candidate


def on_object(point: np.ndarray, cloud: np.ndarray) -> np.ndarray:
    """(2,) where a point (3,) lies on the object the cloud (N, 3) shows: its coordinate along the
    cloud's principal axis (from the centroid) and its distance from that axis."""
    centre = cloud.mean(axis=0)
    axis = np.linalg.svd(cloud - centre, full_matrices=False)[2][0]  # (3,) the longest principal axis
    d = np.asarray(point, float) - centre
    along = float(d @ axis)
    return np.array([along, float(np.linalg.norm(d - along * axis))])


def distance_on_object(a: np.ndarray, b: np.ndarray) -> float:
    """Distance (m) between two `on_object` positions, the axis's sign either way."""
    return float(min(np.hypot(a[0] - b[0], a[1] - b[1]), np.hypot(a[0] + b[0], a[1] - b[1])))


def holding(options: list[Candidate], cloud: np.ndarray, eye: np.ndarray | None, config: HoldConfig,
            slips: list[np.ndarray]) -> tuple[list[Candidate], list[dict]]:
    """The options whose grasps hold (moved down where that makes one hold), in their order, and the
    record's lines for those ruled out; all options, unjudged, when every one is ruled out for its hold
    alone (the cell tries its best rather than stop), none near a slip."""
    judged: dict[int, tuple[np.ndarray | None, str]] = {}  # grasp rank -> the grasp that holds (None: none), why
    kept, ruled, near_slip = [], [], []
    for c in options:
        where = on_object(c.T_base_tcp[:3, 3], cloud)
        close = [distance_on_object(where, s) for s in slips if distance_on_object(where, s) < config.slip_away]
        if close:
            near_slip.append(describe(c, f"ruled out: {1000 * min(close):.0f} mm from a grasp that slipped "
                                         f"(at least {1000 * config.slip_away:.0f} mm away)"))
            continue
        if c.grasp_rank not in judged:
            judged[c.grasp_rank] = _holding_grasp(c.T_base_tcp, cloud, eye, config)
        T, why = judged[c.grasp_rank]
        if T is None:
            ruled.append((c, describe(c, f"ruled out: {why}")))
        else:
            kept.append(replace(c, T_base_tcp=T))
    if not kept and ruled:
        return [c for c, _ in ruled], near_slip
    return kept, near_slip + [line for _, line in ruled]


def _holding_grasp(T: np.ndarray, cloud: np.ndarray, eye: np.ndarray | None,
                   config: HoldConfig) -> tuple[np.ndarray | None, str]:
    """The grasp, or the first move of it down its pad plane, judged to hold (or not judged); None and
    the first judgement's reason when none does."""
    first: Hold = judge_hold(T, cloud, config, eye=eye)
    if first.holds is not False:
        return T, first.reason
    for distance in config.moves:
        moved = moved_down(T, distance)
        if judge_hold(moved, cloud, config, eye=eye).holds:
            return moved, f"moved {1000 * distance:.0f} mm down: {first.reason}"
    return None, first.reason
