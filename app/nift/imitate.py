"""Interaction imitation by pose optimisation (paper Sec. III-C, Eq. 5):

    T* = argmin_T  sum_{x in X}  w(x) | f(x | O_demo) - f(T x | O_target) |_1

with w(x) = 1 / |X| in the paper; ours, for place templates, w(x) ~ exp(-d(x) / s), d(x) the point's
distance to the anchor and s = `place_contact_scale` (contact weighting, see ImitationConfig).

X and f(x | O_demo) come from a template (`app.nift.template`); T maps the anchor frame into the
target cloud's frame, so T* is the anchor's pose there: the gripper pose for a grasp template,
the rack / shelf pose relative to the object for a place template.

Batched over `inits` initialisations: the template centroid c_X moved onto the cloud centroid
c_O, a Haar-random rotation and a small random translation u,

    T x = R (x - c_X) + c_O + t,    R(0) Haar,  t(0) = u ~ U(-init_translation, init_translation)^3

then Adam (lr 1e-2) on (R, t) for up to `iterations` steps, stopping early once no
initialisation has improved its loss by `tolerance` (relative) for `patience` steps. The lowest
final loss wins. Our addition: the step size decays (cosine) to 5 % of lr by the last
iteration - with a constant 1e-2 the pose keeps jittering by millimetres around the optimum
(measured on a demo's own cloud with an early NIF checkpoint: 9 mm / 9 degrees constant,
0.1 mm / 0.1 degrees decayed; scripts/diagnose/diagnose_self_imitation.py).
Optional (`prune_every`, our addition, on by default): drop the worse half of the initialisations
every so many steps, down to `keep`; while more than `keep` are alive (exploration), the loss is
taken over a fixed random subset of `explore_points` template points, then over all of them
(refinement; over a fixed random `refine_points` of them when that is set, the cell's schedule).
Both cut the work where it was spent: 10 initialisations x 500 points for the first steps. Every initialisation's final pose is scored on all points before the best is chosen.
With `diverse` (the cell's schedule) pruning drops a pose that is the same candidate as a better one
(`app.nift.candidates.leaders`) before any other, so one pose per basin survives, and the result
also ranks the distinct poses within a margin of the best (`Imitation.candidates`).

Optional `min_weight` (our addition; the cell's schedule): template points weighted below
min_weight x the largest weight are left out and the rest renormalised - with contact weighting
at 1e-3 a place template keeps 99.9 % of its weight on 168-369 of its 500 points.

Optional demo matching "nearest" (our addition, off by default; `ImitationConfig.place_demo_match`):
instead of the demos' mean feature, each pose is compared with every demo's own features and its
loss is the nearest demo's,

    L(T) = min_d  sum_{x in X}  w(x) | f(x | O_d) - f(T x | O_target) |_1

(the mean of ten mugs' fields is no mug's). Measured on the bench: no gain (docs/additions.md, "Nearest demo").

Optional `feasible` (our addition): a predicate on poses (K, 4, 4) -> (K,) bool from the caller
(e.g. "the fingers would close on something"); pruning drops infeasible initialisations first (the
higher-loss ones first among them: with none feasible it prunes as without a predicate) and
the lowest-loss feasible pose wins (the lowest-loss one when none is feasible).

Rotation parametrisation: the continuous 6-D representation of Zhou et al.
(CVPR 2019) - two columns, Gram-Schmidt - which has no singularity anywhere, 180 degrees included
(axis-angle and quaternions wrap or double-cover there).
"""
from __future__ import annotations

import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import torch
import torch._dynamo  # noqa: F401 - Adam's constructor imports it on first use (1.9 s here): paid at start-up, not in a job

from app.nift.candidates import HALF_TURN_Z, IDENTITY, candidates, leaders
from app.nift.field import Latent, NeuralField, shared_field
from app.nift.imitation_config import ImitationConfig
from app.nift.schedule import cosine
from app.nift.template import FEATURES, Template, point_features
from hardware.se3 import random_rotations


@dataclass
class Imitation:
    """The result: the best anchor pose in the cloud's frame, every init's pose and loss, timings."""

    T: np.ndarray  # (4, 4)
    poses: np.ndarray  # (inits, 4, 4)
    losses: np.ndarray  # (inits,) final mean L1 feature distance per point
    best: int
    iterations: int
    seconds: float
    feasible: np.ndarray | None = None  # (inits,) the caller's predicate at the final poses, if given
    ranked: np.ndarray | None = None  # (K,) indices of the distinct candidates, best first (`app.nift.candidates`)

    @property
    def candidates(self) -> np.ndarray:
        """(K, 4, 4) the distinct candidate poses, best first."""
        return self.poses[self.ranked if self.ranked is not None else [self.best]]

    @property
    def candidate_losses(self) -> np.ndarray:
        """(K,) their losses."""
        return self.losses[self.ranked if self.ranked is not None else [self.best]]


Feasible = Callable[[np.ndarray], np.ndarray]  # poses (K, 4, 4) -> (K,) bool


def use_threads(n: int) -> None:
    """Run torch's CPU work on n intra-op threads (the cell's choice: `app.jobs.job.JobConfig.threads`)."""
    if torch.get_num_threads() != n:
        torch.set_num_threads(n)


def rotation_from_6d(r6: torch.Tensor) -> torch.Tensor:
    """(B, 6) -> (B, 3, 3): Gram-Schmidt on the two 3-vectors; they become the first two columns."""
    a, b = r6[:, :3], r6[:, 3:]
    x = torch.nn.functional.normalize(a, dim=-1)
    y = torch.nn.functional.normalize(b - (x * b).sum(-1, keepdim=True) * x, dim=-1)
    return torch.stack([x, y, torch.cross(x, y, dim=-1)], dim=-1)


def rotation_to_6d(R: torch.Tensor) -> torch.Tensor:
    """(B, 3, 3) -> (B, 6): the first two columns."""
    return torch.cat([R[:, :, 0], R[:, :, 1]], dim=-1)


def point_weights(template: Template, contact_scale: float) -> np.ndarray:
    """Weights (M,) summing to 1: w(x) ~ exp(-(d(x) - min d) / contact_scale), d = the point's distance
    to the anchor; uniform (the paper's mean) when contact_scale is 0 or the template has no distances."""
    d = template.distances
    if not contact_scale or d is None:
        return np.full(len(template.points), 1.0 / len(template.points))
    w = np.exp(-(d - d.min()) / contact_scale)
    return w / w.sum()


def demo_targets(template: Template, match: str) -> np.ndarray:
    """The feature targets (D, M, F) a pose is compared with: the demos' mean (D = 1, "mean") or each
    demo's own features ("nearest")."""
    if match == "mean":
        return template.features[None]
    if template.per_demo is None:
        raise ValueError("matching the nearest demo needs each demo's features: "
                         "load the template with task_templates(..., per_demo=(stage,)) or with_demo_features")
    return template.per_demo


def targets_and_weights(template: Template, config: ImitationConfig) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Eq. 5's template points (M, 3), feature targets (D, M, F) and point weights (M,) summing to 1
    for a template under `config` (points below `config.min_weight` of the largest weight left out)."""
    targets = demo_targets(template, config.demo_match(template.anchor))
    w = point_weights(template, config.contact_scale(template.anchor))
    kept = w >= config.min_weight * w.max()
    return (torch.as_tensor(template.points[kept], dtype=torch.float32),
            torch.as_tensor(targets[:, kept], dtype=torch.float32),
            torch.as_tensor(w[kept] / w[kept].sum(), dtype=torch.float32))


def eq5(f: torch.Tensor, targets: torch.Tensor, w: torch.Tensor) -> torch.Tensor:
    """Eq. 5 per pose (I,): features f (I, M, F) at the posed template points against targets
    (D, M, F), weights w (M,) summing to 1; the nearest target's loss (D = 1: the paper's)."""
    dist = (f[:, None] - targets[None]).abs().sum(dim=-1)  # (I, D, M)
    return (dist * w).sum(dim=-1).min(dim=1).values


def latent_of(field: NeuralField, cloud: np.ndarray) -> Latent:
    """The cloud (N, 3) encoded by `field` without a graph: imitation never trains the encoder."""
    with torch.no_grad():
        return field.encode(cloud)


def losses_at(template: Template, cloud: np.ndarray, poses: np.ndarray, config: ImitationConfig = ImitationConfig(),
              field: NeuralField | None = None, latent: Latent | None = None) -> np.ndarray:
    """Eq. 5 (I,) at given anchor poses (I, 4, 4) in the cloud's (N, 3) frame, with `config`'s
    weighting and demo matching: what `imitate` minimises; `latent`: the cloud already encoded by `field`."""
    field = field or shared_field(FEATURES[template.feature])
    X, targets, w = targets_and_weights(template, config)  # (M, 3), (D, M, F), (M,)
    x = np.einsum("iab,mb->ima", poses[:, :3, :3], X.double().numpy()) + poses[:, None, :3, 3]  # (I, M, 3)
    with torch.no_grad():
        latent = latent if latent is not None else latent_of(field, cloud)
        f = point_features(field, template.feature, latent, torch.as_tensor(x, dtype=torch.float32))
        return eq5(f, targets, w).numpy().astype(np.float64)


def lr_at(config: ImitationConfig, iteration: int) -> float:
    """Cosine decay from lr to lr * lr_final_ratio over the iteration budget."""
    return cosine(config.lr, config.lr * config.lr_final_ratio, iteration / config.iterations)


def _subset(opt: torch.optim.Adam, params: list[torch.Tensor], keep: torch.Tensor):
    """New leaf parameters holding rows `keep`, and an Adam that carries their moment estimates."""
    new = [p.detach()[keep].clone().requires_grad_(True) for p in params]
    new_opt = torch.optim.Adam(new, lr=opt.param_groups[0]["lr"])
    for old_p, new_p in zip(params, new):
        state = opt.state.get(old_p)
        if state:
            new_opt.state[new_p] = {"step": state["step"].clone(), "exp_avg": state["exp_avg"][keep].clone(),
                                    "exp_avg_sq": state["exp_avg_sq"][keep].clone()}
    return new, new_opt


@contextmanager
def frozen(module: torch.nn.Module):
    """Parameters without gradients inside the block: the backward pass then computes only the
    gradient with respect to the query points, not the weight gradients (half its cost)."""
    was = [p.requires_grad for p in module.parameters()]
    module.requires_grad_(False)
    try:
        yield module
    finally:
        for p, flag in zip(module.parameters(), was):
            p.requires_grad_(flag)


def imitate(template: Template, cloud: np.ndarray, config: ImitationConfig = ImitationConfig(),
            field: NeuralField | None = None, feasible: Feasible | None = None,
            starts: np.ndarray | None = None, latent: Latent | None = None) -> Imitation:
    """Optimise Eq. 5 for a target cloud (N, 3); `field` defaults to the template's shipped field;
    `feasible` (optional) rules poses out, see the module doc; `starts` (I, 4, 4), optional: anchor
    poses to start from, beside the `config.inits` random ones; `latent`: the cloud already encoded by
    `field` (the encoder runs once per cloud for both templates)."""
    cloud = np.asarray(cloud, dtype=np.float64)
    if cloud.ndim != 2 or cloud.shape[1] != 3 or len(cloud) < 16:
        raise ValueError(f"the target cloud must be (N, 3) with N >= 16, got shape {cloud.shape}")
    if not all(np.isfinite(a).all() for a in (template.points, template.features, template.per_demo) if a is not None):
        raise ValueError(f"the {template.anchor} template holds NaN or infinite values: rebuild it from its demos")
    start = time.perf_counter()
    field = field or shared_field(FEATURES[template.feature])
    width = field.config.out_dim if template.feature == "scf" else field.config.feature_dim
    if template.features.shape[-1] != width:
        raise ValueError(f"the {template.anchor} template's features are {template.features.shape[-1]} wide, but the "
                         f"{template.feature} field gives {width}: rebuild the template from its demos")
    with frozen(field):
        latent = latent if latent is not None else latent_of(field, cloud)
        return _optimise(template, cloud, config, field, latent, start, feasible, starts)


def _poses(r6: torch.Tensor, t: torch.Tensor, c_X: torch.Tensor, c_O: torch.Tensor) -> np.ndarray:
    """(I, 4, 4) float64 poses T x = R (x - c_X) + c_O + t of the parameters (I, 6), (I, 3)."""
    with torch.no_grad():  # in float32, then widened: every downstream check sees the poses it always saw
        R = rotation_from_6d(r6)
        trans = c_O + t - torch.einsum("iab,b->ia", R, c_X)
        R, trans = R.double(), trans.double()
    T = np.tile(np.eye(4), (len(R), 1, 1))
    T[:, :3, :3], T[:, :3, 3] = R.numpy(), trans.numpy()
    return T


def _survivors(loss: torch.Tensor, poses: np.ndarray | None, feasible: Feasible | None, config: ImitationConfig,
               symmetries: tuple[np.ndarray, ...], n: int) -> torch.Tensor:
    """Rows (n,) a pruning step keeps, by rank: feasible leaders, then feasible followers (the same
    candidate as a better pose, `app.nift.candidates`; only with `config.diverse`), then the
    infeasible ones in the same order. The predicate is asked in that order only until n feasible
    rows are found: the rest cannot make the cut."""
    rank = loss.clone()
    span = float(rank.max() - rank.min()) + 1.0
    if config.diverse:
        _, followers = leaders(poses, loss.numpy(), config.candidates, symmetries)
        rank[torch.as_tensor(followers, dtype=torch.long)] += span
    order = torch.argsort(rank)
    if feasible is None:
        return order[:n]
    kept, infeasible = [], []
    for row in order.tolist():  # one pose at a time: a feasibility check (a collision query) costs ~1 ms
        (kept if feasible(poses[row:row + 1])[0] else infeasible).append(row)
        if len(kept) == n:
            break
    return torch.as_tensor((kept + infeasible)[:n], dtype=torch.long)


def memoised(feasible: Feasible) -> Feasible:
    """The predicate, asked once per distinct pose: a pose dropped by the pruning keeps its last value,
    and the final check of every pose meets it again."""
    seen: dict[bytes, bool] = {}

    def check(poses: np.ndarray) -> np.ndarray:
        keys = [T.tobytes() for T in poses]
        new = [i for i, k in enumerate(keys) if k not in seen]
        if new:
            seen.update(zip((keys[i] for i in new), map(bool, feasible(poses[new]))))
        return np.array([seen[k] for k in keys], dtype=bool)

    return check


def symmetries_of(template: Template) -> tuple[np.ndarray, ...]:
    """The anchor's symmetries: a two-finger gripper's half-turn about its approach axis."""
    return (np.eye(4), HALF_TURN_Z) if template.anchor == "gripper" else IDENTITY


def _initial(config: ImitationConfig, rng: np.random.Generator, c_X: torch.Tensor, c_O: torch.Tensor,
             starts: np.ndarray | None) -> tuple[torch.Tensor, torch.Tensor]:
    """Initial (R (I, 3, 3), t (I, 3)): `config.inits` random ones (module doc), then one per start
    pose S (R = S_R, t = S_t - c_O + R c_X, so that T = S)."""
    R0 = torch.as_tensor(random_rotations(config.inits, rng), dtype=torch.float32)
    t0 = torch.as_tensor(rng.uniform(-config.init_translation, config.init_translation, (config.inits, 3)),
                         dtype=torch.float32)
    if starts is None or len(starts) == 0:
        return R0, t0
    S = torch.as_tensor(np.asarray(starts)[:, :3], dtype=torch.float32)  # (S, 3, 4)
    tS = S[:, :, 3] - c_O + torch.einsum("sab,b->sa", S[:, :, :3], c_X)
    return torch.cat([R0, S[:, :, :3]]), torch.cat([t0, tS])


def _optimise(template: Template, cloud: np.ndarray, config: ImitationConfig, field: NeuralField, latent: Latent,
              start: float, feasible: Feasible | None = None, starts: np.ndarray | None = None) -> Imitation:
    """The loop of `imitate` (the field's parameters frozen)."""
    symmetries = symmetries_of(template)
    feasible = memoised(feasible) if feasible is not None else None
    rng = np.random.default_rng(config.seed)
    X, target, w = targets_and_weights(template, config)  # (M, 3), (D, M, F), (M,) sum 1
    c_X, c_O = X.mean(dim=0), torch.as_tensor(cloud.mean(axis=0), dtype=torch.float32)
    R0, t0 = _initial(config, rng, c_X, c_O, starts)
    inits = len(R0)
    r6 = rotation_to_6d(R0).requires_grad_(True)  # (I, 6)
    t = t0.clone().requires_grad_(True)  # (I, 3)
    opt = torch.optim.Adam([r6, t], lr=config.lr)
    feature = template.feature

    def losses(r6: torch.Tensor, t: torch.Tensor, rows: torch.Tensor | None = None) -> torch.Tensor:
        """Eq. 5 per initialisation (I,), over the template's points or the subset `rows`."""
        Xs, target_s, ws = (X, target, w) if rows is None else (X[rows], target[:, rows], w[rows] / w[rows].sum())
        R = rotation_from_6d(r6)  # (I, 3, 3)
        x = torch.einsum("iab,mb->ima", R, Xs - c_X) + c_O + t[:, None]  # (I, M, 3)
        return eq5(point_features(field, feature, latent, x), target_s, ws)

    exploring = bool(config.prune_every) and inits > config.keep and 0 < config.explore_points < len(X)
    rows = torch.as_tensor(rng.choice(len(X), config.explore_points, replace=False)) if exploring else None
    refine = (torch.as_tensor(rng.choice(len(X), config.refine_points, replace=False))
              if exploring and 0 < config.refine_points < len(X) else None)  # None: refine on every point
    alive = torch.arange(inits)  # original index of each row still optimised
    final_r6, final_t = r6.detach().clone(), t.detach().clone()
    best = torch.full((inits,), float("inf"))
    stale, iterations = 0, 0
    for iterations in range(1, config.iterations + 1):
        for group in opt.param_groups:  # cosine decay to lr_final: fine steps at the end
            group["lr"] = lr_at(config, iterations)
        loss = losses(r6, t, rows)
        opt.zero_grad()
        loss.sum().backward()
        opt.step()
        current = loss.detach()
        improved = current < best[alive] * (1 - config.tolerance)
        best[alive] = torch.minimum(best[alive], current)
        stale = 0 if improved.any() else stale + 1
        if stale >= config.patience:
            break
        if config.prune_every and iterations % config.prune_every == 0 and len(alive) > config.keep:
            poses = _poses(r6, t, c_X, c_O) if config.diverse or feasible is not None else None  # only if ranked on
            keep = _survivors(current, poses, feasible, config, symmetries, max(config.keep, len(alive) // 2))
            final_r6[alive], final_t[alive] = r6.detach(), t.detach()  # the dropped ones keep these
            alive = alive[keep]
            (r6, t), opt = _subset(opt, [r6, t], keep)
            if rows is not None and len(alive) <= config.keep:  # exploration over: refine (`refine_points`, else all)
                rows, stale = refine, 0
                best[alive] = float("inf")
    with torch.no_grad():
        final_r6[alive], final_t[alive] = r6, t
        final = losses(final_r6, final_t).numpy().astype(np.float64)  # every init on all points: they compare
    poses = _poses(final_r6, final_t, c_X, c_O)
    ok = feasible(poses) if feasible is not None else None
    ranked = candidates(poses, final, config.candidates, symmetries, ok)
    k = int(ranked[0])  # the lowest-loss feasible pose (the lowest-loss one when none is feasible)
    return Imitation(poses[k], poses, final, k, iterations, time.perf_counter() - start, ok, ranked)

