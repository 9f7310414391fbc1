"""Grasps that will hold, and away from one that slipped (our addition; the judgement is
`app.predict.grasp_hold`).

Before the plan, each candidate's grasp is judged on the cloud the camera saw. A grasp that would
slide out is tried again moved down its pad plane by `HoldConfig.moves` (off a cap that narrows to
the top, onto the neck or the body), no farther than the palm stays clear of the cloud; when no move
holds, it is ruled out and the record says why.
After a slip, grasps within `HoldConfig.slip_away` of the slipped one are ruled out too. Positions on
the object are compared in the cloud's principal-axis frame - the position along the longest axis, of
either sign, and the distance from it - so the object may have fallen, turned about its axis, or
flipped end over end since. When every option is ruled out, the job tries them all as they are.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from app.jobs.choice import describe
from app.predict.grasp_hold import Hold, HoldConfig, judge_hold, moved_down
from app.predict.pairs import Candidate
from app.predict.palm_clearance import palm_overlap


def object_axis(cloud: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cloud's (N, 3) centroid (3,) and longest principal axis (3,)."""
    centre = cloud.mean(axis=0)
    return centre, np.linalg.svd(cloud - centre, full_matrices=False)[2][0]


def on_object(point: np.ndarray, axis: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """(2,) where a point (3,) lies on the object whose `object_axis` is given: its coordinate along the
    axis (from the centroid) and its distance from it."""
    centre, direction = axis
    d = np.asarray(point, float) - centre
    along = float(d @ direction)
    return np.array([along, float(np.linalg.norm(d - along * direction))])


def distance_on_object(a: np.ndarray, b: np.ndarray) -> float:
    """Distance (m) between two `on_object` positions, the axis's sign either way."""
    return float(min(np.hypot(a[0] - b[0], a[1] - b[1]), np.hypot(a[0] + b[0], a[1] - b[1])))


def holding(options: list[Candidate], cloud: np.ndarray, eye: np.ndarray | None, config: HoldConfig,
            slips: list[np.ndarray]) -> tuple[list[Candidate], list[dict]]:
    """The options whose grasps hold and keep away from every slip - moved down where that makes one
    so - in their order, and the record's lines for those ruled out. When every option is ruled out, all
    of them, as they are: the cell tries its best rather than stop."""
    judged: dict[int, tuple[np.ndarray | None, str, bool]] = {}  # grasp rank -> grasp (None: none), why, near a slip
    kept, ruled = [], []
    axis = object_axis(cloud) if slips else None  # slips are compared on the object, in its own axes
    for c in options:
        if c.grasp_rank not in judged:
            judged[c.grasp_rank] = _holding_grasp(c.T_base_tcp, cloud, eye, config, slips, axis)
        T, why, near = judged[c.grasp_rank]
        if T is None:
            ruled.append((c, describe(c, f"ruled out: {why}"), near))
        else:
            kept.append(replace(c, T_base_tcp=T))
    if not kept and ruled:  # nothing better to do than try them: a cell that stops gains nothing
        return [c for c, *_ in ruled], []
    return kept, [line for _, line, _ in ruled]


def _holding_grasp(T: np.ndarray, cloud: np.ndarray, eye: np.ndarray | None, config: HoldConfig,
                   slips: list[np.ndarray], axis: tuple | None) -> tuple[np.ndarray | None, str, bool]:
    """The grasp, or the first move of it down its pad plane, that keeps `slip_away` from every slip and
    is judged to hold (the grasp itself may be unjudged, a move must be judged to hold); else None, the
    reason against the grasp itself, and whether that reason is a slip near it."""
    near = _nearest_slip(T, axis, slips)
    first: Hold = judge_hold(T, cloud, config, eye=eye)
    if near >= config.slip_away and first.holds is not False:
        return T, first.reason, False
    for distance in config.moves:
        moved = moved_down(T, distance)
        if palm_overlap(moved, cloud, 0.0) > 0.0:  # the palm would be on what it holds: no deeper
            break
        if _nearest_slip(moved, axis, slips) >= config.slip_away and judge_hold(moved, cloud, config, eye=eye).holds:
            return moved, f"moved {1000 * distance:.0f} mm down: " + (first.reason if near >= config.slip_away
                                                                      else "away from a grasp that slipped"), False
    if near < config.slip_away:
        return None, (f"{1000 * near:.0f} mm from a grasp that slipped (at least {1000 * config.slip_away:.0f} mm "
                      f"away), and no move down holds"), True
    return None, first.reason, False


def _nearest_slip(T: np.ndarray, axis: tuple | None, slips: list[np.ndarray]) -> float:
    """Distance (m) on the object (`object_axis`) from the grasp's TCP to the nearest slipped grasp (inf:
    none slipped)."""
    if not slips:
        return np.inf
    where = on_object(T[:3, 3], axis)
    return min(distance_on_object(where, s) for s in slips)
