"""The place chosen after the second look (`app.jobs.second_look`): the handle hole a held view shows,
the place imitated again on the fused views, and the first look's places for the held grasp, in
that order; the rest of the job planned from where the arm is."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from app.failures import NoCandidate, PerceptionFailure, PlanningFailure
from app.jobs.context import JobContext
from app.jobs.record import check_held, ur
from app.jobs.second_look import second_look
from app.motion.planner import OBJECT, FingerWidths, Planner
from app.perception import resample
from app.predict.pairs import Candidate
from app.predict.hole_places import with_hole_pairs
from hardware.se3 import transform_points


def look_and_place(job: JobContext, planner: Planner, plan, chosen: Candidate, options: list, cloud: np.ndarray):
    """The second look (`app.jobs.second_look`): show the held object, imitate the place again on both
    views, and plan the rest from where the arm is - with the first look's places for this grasp when
    no new one plans (or nothing was seen). Returns the plan to carry on with and where the object
    should end (`sent`)."""
    T_grasp, width = plan.T_base_grasp, job.gripper.width
    widths = FingerWidths(width, width, job.release_width(width))
    T_above = job.T_base_fixture_placed
    first = [chosen, *(c for c in options if c.grasp_rank == chosen.grasp_rank and c.place_rank != chosen.place_rank)]
    with job.stage("look"):
        holes = [(c, cloud, False) for c in first if c.place_rank < 0]  # the first look's hole places, first
        try:
            views = second_look(job.arm, job.camera, planner, job.T_base_cam, job.points, T_grasp, width,
                                job.config.motion.end_tolerance, job.config.look, job.config.perception)
        except (PerceptionFailure, PlanningFailure) as exc:  # nothing seen, or no way to show it: the first look
            views, look = None, {"used": False, "why": str(exc)}
        check_held(job.gripper, "second look")
        tries = []  # (pair, the cloud it moves, whether the look gave it)
        if views is not None:
            points = np.concatenate([job.points, *views])
            fused = resample(points, len(cloud), job.config.perception.seed)
            job.log.cloud(points, "second look")
            # the carried object's model: what the first look saw and what the held views show
            job.scene.add_cloud(OBJECT, np.concatenate([job.scene.solids[OBJECT], *views]))
            starts = np.stack([c.T_base_fixture_seen for c in first])
            look = {"used": False, "new_points": int(sum(len(v) for v in views))}
            tries = [(c, fused, True) for c in job.placer(fused, chosen.T_base_tcp, starts)[: job.config.most_plans]]
            if job.looks_for_hole():
                held, look["hole"], shown = held_hole(job, chosen, views if holes else [*views, points])
                if held:
                    shown = resample(shown, len(cloud), job.config.perception.seed)  # the mug as that cloud shows it
                    holes = [(c, shown, True) for c in held] + holes
        tries = holes + tries + [(c, cloud, False) for c in first[: job.config.most_plans] if c.place_rank >= 0]
        q, whys, look_whys = job.arm.getActualQ(), [], []
        for c, seen, looked in tries:
            c = replace(c, T_base_fixture=T_above)  # placed clear of a peg, as the first look's pairs
            try:
                rest = planner.place_from(q, T_grasp, c.motion @ T_grasp, job.place_line(seen)(c), widths)
            except PlanningFailure as exc:
                whys.append(str(exc))
                if looked:
                    look_whys.append(whys[-1])
                continue
            if looked:
                look.update({"used": True, "place_rank": c.place_rank, **moved(plan, rest)})
            job.result.look = _with_why(look, views is not None, look_whys)
            job.result.poses["place"] = ur(rest.T_base_place)
            job.result.notes += rest.notes
            return rest, transform_points(c.motion, seen)
        job.result.look = _with_why(look, views is not None, look_whys)
        raise NoCandidate(f"none of {len(tries)} places could be planned for the held grasp; the best: "
                        f"{whys[0] if whys else 'no place'}")


def held_hole(job: JobContext, chosen: Candidate, clouds: list[np.ndarray]
              ) -> tuple[list[Candidate], dict, np.ndarray | None]:
    """The hole places for the held grasp from the first of `clouds` (M_i, 3), grasp-time frame, that
    shows the hole - a view alone shows the object as it sits in the hand now, which may have turned
    on closing - what was found (with the index of that cloud), and that cloud: its points, not a
    fusion that may hold the mug twice, choose the line onto the peg (`app.motion.place_line`)."""
    found = {"found": False, "why": "no view shows the handle hole"}
    for i, points in enumerate(clouds):
        pairs, found = with_hole_pairs([chosen], points, job.hang)
        if found["found"]:
            return [c for c in pairs if c.place_rank < 0], {**found, "view": i}, points
    return [], found, None


def _with_why(look: dict, looked: bool, look_whys: list[str]) -> dict:
    """The look's record, saying why its best place was not taken when it looked and none of its
    places was (the first of `look_whys`, the reasons its places failed)."""
    if looked and not look["used"]:
        look["why"] = look_whys[0] if look_whys else "no place"
    return look


def moved(plan, rest) -> dict:
    """How far the second look moved the place from the first plan's (or that the first had none)."""
    if plan.T_base_place is None:
        return {"pick_only": True}
    return {"place_moved_m": round(float(np.linalg.norm(rest.T_base_place[:3, 3] - plan.T_base_place[:3, 3])), 4)}
