"""Grasp and place poses for a target cloud, by NIFT or a baseline, in one code path (paper Table I rows).

Methods (`app.predict.methods`): "<query>-<feature>" with query in {ibs, bps} and feature in {nif, scf,
ndf} (template imitation, Eq. 5), "nift" = "ibs-nif", and "cpd" (demo registration); what to do is a
`PredictConfig` (`app.predict.config`). Every method answers:

- T_base_tcp: the grasp pose of the gripper in the cloud's (base) frame;
- T_base_fixture_seen: where the rack / shelf would have to be, relative to the object as it is
  now, for the object to sit on it as in the demos;
- motion = T_base_fixture @ inv(T_base_fixture_seen): the rigid motion that takes the object from
  where it is to its place on the real fixture. The object's goal pose is motion @ T_base_obj
  (when it is known, as in simulation), and with a rigid grasp the gripper's place pose is
  motion @ T_base_tcp.

Template methods rank their candidate poses by feasibility first (`app.predict.feasibility`, our addition):
a grasp must close on cloud points, a place must be one the grasp could carry the object to as in
the demos. Then both poses are centred on the cloud (our addition): the grasp on the points between
the fingers (`app.predict.grasp_centering`), a hang on the peg in the middle of the hole's gap
(`app.predict.peg_centering`; fixtures without a peg are left alone) - on by default, for every method
alike. Optionally (`PredictConfig.align`, off by default: it needs the normals a fused cloud gives and one
Kinect view does not) the grasp is first turned so its fingers close along the normal of the wall
between them (`app.predict.grasp_alignment`, our addition).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from app.layout import CellLayout
from app.nift.cpd import best_registration
from app.nift.field import shared_field
from app.nift.imitate import imitate, latent_of, losses_at, symmetries_of
from app.nift.template import FEATURES, field_override
from app.objects import Fixture, fixture
from app.predict.pairs import Candidate, excess, ranked_pairs
from app.predict.carried_grasps import carried_pairs, carried_places
from app.predict.feasibility import (Reach, all_of, carries_like_demos,
                                     demo_carries, grips_something, reaches)
from app.predict.grasp_alignment import align_grasp
from app.predict.grasp_centering import center_grasp
from app.predict.grasp_starts import gravity_starts
from app.predict.config import PredictConfig
from app.predict.methods import Family, Method
from app.predict.methods import method as method_record
from app.predict.peg_centering import center_on_peg
from app.tasks.demo_library import (DEMOS_DIR, STAGES, stage_anchor, task_demos,
                               task_templates)
from app.tasks.task import Task
from hardware.se3 import invert


@dataclass
class Prediction:
    """What a method predicts for one cloud, with its costs; `candidates` (template methods) are the
    grasp and place pairs a cell may execute instead, best first (`app.predict.pairs`)."""

    method: str
    T_base_tcp: np.ndarray
    T_base_fixture_seen: np.ndarray
    motion: np.ndarray
    losses: dict[str, list[float]] = field(default_factory=dict)
    iterations: dict[str, int] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)
    candidates: list[Candidate] = field(default_factory=list)

    @property
    def T_base_tcp_place(self) -> np.ndarray:
        """The gripper's pose at the place, if the grasp holds the object rigidly."""
        return self.motion @ self.T_base_tcp

    @property
    def T_base_fixture(self) -> np.ndarray:
        """The real fixture's pose the motion was computed for (motion = T_base_fixture @ inv(seen))."""
        return self.motion @ self.T_base_fixture_seen

    def options(self) -> list[Candidate]:
        """The pairs to try, best first: the candidates, or the single prediction."""
        return self.candidates or [Candidate(self.T_base_tcp, self.T_base_fixture_seen, self.T_base_fixture)]

    def record(self) -> dict:
        """JSON-ready."""
        return {"method": self.method, "T_base_tcp": self.T_base_tcp.round(6).tolist(),
                "T_base_tcp_place": self.T_base_tcp_place.round(6).tolist(),
                "motion": self.motion.round(6).tolist(), "losses": self.losses, "iterations": self.iterations,
                "seconds": self.seconds, "candidates": len(self.candidates)}


def predict(t: Task, cloud: np.ndarray, config: PredictConfig = PredictConfig(),
            T_base_fixture: np.ndarray | None = None, reachable: Reach | None = None) -> Prediction:
    """Grasp pose and place motion for a target cloud (N, 3) in the base frame, as `config` says
    (`PredictConfig`: the method, the demos, other field weights, the imitation schedule, the
    refinements); `T_base_fixture`: the real fixture's pose (default: the cell's layout); `reachable`:
    whether the cell can put its gripper at a grasp pose - given, a template method's feasible grasps
    are also ones it can reach."""
    pred = _predict(t, cloud, config, method_record(config.method), T_base_fixture, reachable)
    center, align = config.center, config.align
    pred.T_base_tcp = refine_grasp(pred.T_base_tcp, cloud, center=center, align=align)
    peg = fixture(t.fixture)  # built once for every candidate
    if center:
        seen = center_on_peg(pred.T_base_fixture_seen, cloud, peg)
        if not np.array_equal(seen, pred.T_base_fixture_seen):  # unmoved (the shelf): keep the motion bit for bit
            pred.motion = pred.motion @ pred.T_base_fixture_seen @ invert(seen)  # T_base_fixture @ inv(seen)
            pred.T_base_fixture_seen = seen
    pred.candidates = [refine_candidate(c, peg, cloud, center=center, align=align) for c in pred.candidates]
    return pred


def refine_candidate(c: Candidate, peg: Fixture, cloud: np.ndarray, *, center: bool, align: bool) -> Candidate:
    """A candidate pair refined as `predict` refines its best poses (`peg`: the task's fixture)."""
    seen = center_on_peg(c.T_base_fixture_seen, cloud, peg) if center else c.T_base_fixture_seen
    return replace(c, T_base_tcp=refine_grasp(c.T_base_tcp, cloud, center=center, align=align),
                   T_base_fixture_seen=seen)


def refine_grasp(T_base_tcp: np.ndarray, cloud: np.ndarray, *, center: bool, align: bool) -> np.ndarray:
    """A predicted grasp turned onto the wall its (centred) fingers would close on (`align`), then
    centred between them (`center`); a grasp the alignment leaves unturned is centred once, as without it."""
    seen = center_grasp(T_base_tcp, cloud) if center else T_base_tcp
    if not align:
        return seen
    turned = align_grasp(seen, cloud)
    if np.array_equal(turned, seen):
        return seen
    return center_grasp(turned, cloud) if center else turned  # what lies between the fingers moved


def _predict(t: Task, cloud: np.ndarray, settings: PredictConfig, m: Method, T_base_fixture: np.ndarray | None,
             reachable: Reach | None = None) -> Prediction:
    """`predict` before the grasp is centred."""
    directory = settings.demos or DEMOS_DIR / t.demos
    if T_base_fixture is None:
        T_base_fixture = CellLayout().fixture_pose(t.fixture)
    if m.family is Family.REGISTRATION:
        return _predict_cpd(settings.method, t, cloud, T_base_fixture, directory)
    if not m.template:
        raise ValueError(f"method {m.name} reads the simulator's true poses; it has no predictor from a cloud")
    method, query, feature, nif = settings.method, m.query, m.feature, settings.fields
    config, feasible, carried_grasps = settings.imitation, settings.feasible, settings.carried_grasps
    nearest = tuple(s for s in STAGES if config.demo_match(stage_anchor(t, s)) == "nearest")  # per-demo features
    templates = task_templates(t, directory, query, feature, nif=nif, per_demo=nearest)
    field = shared_field(field_override(feature, nif) or FEATURES[feature])  # once for both templates
    latent = latent_of(field, cloud)  # once for every imitation and loss on this cloud
    reach = reachable if feasible else None
    grips = all_of(grips_something(cloud), reaches(reach) if reach else None) if feasible else None
    demos = task_demos(directory) if config.grasp_start_turns or feasible or carried_grasps else None
    begin = gravity_starts(demos, cloud, config.grasp_start_turns) if config.grasp_start_turns else None
    grasp = imitate(templates["grasp"], cloud, config, field, grips, begin, latent)
    demos_carried = demo_carries(demos) if feasible or carried_grasps else None
    carried = demos_carried if feasible else None
    carry = carries_like_demos(grasp.T, carried) if feasible else None
    starts = carried_places(grasp.candidates, demos_carried) if carried_grasps else None
    place = imitate(templates["place"], cloud, config, field, carry, starts, latent)
    pairs = ranked_pairs(grasp, place, T_base_fixture, carried)
    if carried_grasps:
        pairs += carried_pairs(grasp, place, T_base_fixture, demos_carried,
                               lambda G: losses_at(templates["grasp"], cloud, G, config, field, latent), grips,
                               symmetries_of(templates["grasp"]), config.candidates, len(grasp.candidates))
        pairs.sort(key=lambda c: c.score)
    return Prediction(method, grasp.T, place.T, T_base_fixture @ invert(place.T),
                      {"grasp": grasp.losses.round(5).tolist(), "place": place.losses.round(5).tolist()},
                      {"grasp": grasp.iterations, "place": place.iterations},
                      {"grasp": round(grasp.seconds, 3), "place": round(place.seconds, 3)}, pairs)


def predict_place(t: Task, cloud: np.ndarray, T_base_tcp: np.ndarray, settings: PredictConfig = PredictConfig(),
                  T_base_fixture: np.ndarray | None = None, starts: np.ndarray | None = None) -> list[Candidate]:
    """Place candidates, best first, for an object held by the grasp T_base_tcp, from a cloud (N, 3) of
    it as it stood when grasped (the second look's fused cloud, `app.jobs.second_look`): the place
    template imitated from random starts, from the demo's carry of this grasp
    (`app.predict.carried_grasps.carried_places`) and from `starts` (K, 4, 4), the places that carry
    like the demos with this grasp preferred; none for a method without templates (cpd). The settings'
    field weights are not used: the place is imitated on the template's own stored features."""
    m = method_record(settings.method)
    if not m.template:
        return []
    directory = settings.demos or DEMOS_DIR / t.demos
    T_base_fixture = CellLayout().fixture_pose(t.fixture) if T_base_fixture is None else T_base_fixture
    config, center = settings.imitation, settings.center
    template = task_templates(t, directory, m.query, m.feature)["place"]
    carried = demo_carries(task_demos(directory))
    begin = carried_places(T_base_tcp[None], carried)
    begin = begin if starts is None or len(starts) == 0 else np.concatenate([begin, starts])
    place = imitate(template, cloud, config, None, carries_like_demos(T_base_tcp, carried), begin)
    ok = place.feasible[place.ranked] if place.feasible is not None else np.ones(len(place.ranked), bool)
    sp = excess(place.candidate_losses)
    peg = fixture(t.fixture)
    return [Candidate(T_base_tcp, center_on_peg(P, cloud, peg) if center else P, T_base_fixture, float(sp[j]), 0, j)
            for j, P in enumerate(place.candidates) if ok[j]]


def _predict_cpd(method: str, t: Task, cloud: np.ndarray, T_base_fixture: np.ndarray, directory: Path) -> Prediction:
    start = time.perf_counter()
    demos = task_demos(directory)
    k, reg = best_registration([d.cloud for d in demos], cloud)
    seen = reg.transfer(demos[k].place_anchor())
    seconds = round(time.perf_counter() - start, 3)
    return Prediction(method, reg.transfer(demos[k].T_base_tcp), seen, T_base_fixture @ invert(seen),
                      {"registration_sigma2": [reg.sigma2]}, {}, {"registration": seconds})
