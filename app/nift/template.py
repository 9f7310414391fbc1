"""Neural Interaction Template (NIT, paper Sec. III-B and III-D): query points in the anchor's frame
and the features they have in the demo objects' fields.

One demo d: the anchor A (gripper, rack or shelf; a mesh in its own frame) at pose T_d (the demo
object's cloud frame, usually the robot base), the demo object's cloud O_d. Query points X_d:

    ibs: importance-sampled on the IBS between A (posed) and O_d   (the paper's NIT)
    bps: uniform in A's bounding box                                 (NDF's query points, a baseline)

stored in the anchor frame, so all demos share one frame. Several demos: the union of their
points is resampled back to M points with probability proportional to a density weight,

    w(x) = 1 / mean_{k nearest} |x - x_k|,   k = number of demos    (more weight where demos agree)

and the template feature of a point is the mean over demos of f(T_d x | O_d) (each demo's own ones
stay in memory, `Template.per_demo`, for nearest-demo matching; files keep the mean). Each point also keeps
its distance to the anchor's surface (0 inside it), which imitation may use to weight the points
near the contact (`ImitationConfig.contact_scale`, our addition).
Features: "nif" (all NIF decoder activations), "ndf" (all NDF activations), "scf" (the NIF's
predicted SCF c_0..c_n).
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import torch
from scipy.spatial import cKDTree

from app.io_utils import WrongFormat, read_npz, write_npz
from app.nift.field import Latent, NeuralField, field_path, load_field
from app.nift.ibs import compute_ibs
from app.nift.raycast import scene_of, signed_distance
from hardware.se3 import invert, transform_points

FORMAT = "nift-nit/2"
OLDER_FORMATS = ("nift-nit/1",)  # readable headers, but no distances: rebuild from the demos
QUERIES = ("ibs", "bps")
HEADER_KEYS = ("anchor", "query", "feature", "field", "demos")  # what a template file's header must hold
FEATURES = {"nif": "nif", "ndf": "ndf", "scf": "nif"}  # feature kind -> the field it comes from


def field_override(feature: str, weights: str | Path | None) -> str | Path | None:
    """Other weights for the field a feature kind comes from, None for the shipped one. `weights` is
    a NIF file (it replaces the field of the "nif" and "scf" kinds) or a directory holding nif.pt and
    ndf.pt (it replaces both fields)."""
    if weights is None:
        return None
    kind = FEATURES[feature]
    if Path(weights).is_dir():
        path = Path(weights) / f"{kind}.pt"
        if not path.is_file():
            raise FileNotFoundError(f"no {kind}.pt in the fields directory {weights}")
        return path
    return weights if kind == "nif" else None


def weights_id(weights: str | Path) -> str:
    """The identity of a `field_override` argument: a file's `field_id`, or a directory's two."""
    if Path(weights).is_dir():
        return " ".join(field_id(field_override(f, weights)) for f in ("nif", "ndf"))
    return field_id(weights)


class StaleTemplate(ValueError):
    """A template built with other field weights than the ones in use: rebuild it from its demos."""


@dataclass
class Template:
    """Query points (anchor frame) with their demo-averaged features."""

    points: np.ndarray  # (M, 3) anchor frame
    features: np.ndarray  # (M, F)
    anchor: str  # "gripper", "rack", "shelf"
    query: str  # "ibs" or "bps"
    feature: str  # "nif", "ndf" or "scf"
    field_id: str  # which weights made the features (name + sha256 prefix)
    demos: list[str] = field(default_factory=list)
    distances: np.ndarray | None = None  # (M,) each point's distance to the anchor's surface, metres
    per_demo: np.ndarray | None = None  # (D, M, F) each demo's own features (mean = features); not saved


def field_id(name_or_path: str | Path) -> str:
    """A field's identity: its name and the first 12 hex digits of its weights' sha256."""
    path = field_path(name_or_path)
    if not path.is_file():
        raise FileNotFoundError(f"no field weights at {path}")
    return f"{Path(path).stem}:{hashlib.sha256(path.read_bytes()).hexdigest()[:12]}"


def point_features(field: NeuralField, feature: str, latent: Latent, points) -> torch.Tensor:
    """Features (B, T, F) of a template kind ("nif", "ndf": activations; "scf": predicted SCF) at
    points (B, T, 3) in an encoded cloud's field, differentiable in the points."""
    if feature == "scf":
        return field.predict(latent, points)
    return field.features(latent, points)


def query_points(kind: str, anchor_mesh, T_frame_anchor: np.ndarray, cloud: np.ndarray, n: int,
                 seed: int = 0) -> np.ndarray:
    """Query points (n, 3) of one demo in the anchor frame."""
    if kind not in QUERIES:
        raise ValueError(f"unknown query points {kind!r}; choose one of {', '.join(QUERIES)}")
    rng = np.random.default_rng(seed)
    if kind == "bps":
        lo, hi = anchor_mesh.bounds
        return rng.uniform(lo, hi, size=(n, 3))
    posed = anchor_mesh.copy().apply_transform(T_frame_anchor)
    ibs = compute_ibs(posed, clear_of(posed, cloud), n_points=n, seed=seed)
    return transform_points(invert(T_frame_anchor), ibs.points)


def clear_of(mesh, cloud: np.ndarray, gap: float = 0.002, max_share: float = 0.05) -> np.ndarray:
    """The cloud without points inside the anchor or within `gap` of it: sensor noise puts a few
    points of a hung mug's handle inside the peg. More than `max_share` of them is a bad demo."""
    inside = signed_distance(scene_of(mesh), cloud) < gap
    if inside.mean() > max_share:
        raise ValueError(f"{inside.mean():.0%} of the object's cloud lies inside or against the anchor: "
                         "the demo's pose is in collision")
    return cloud[~inside]


def density_resample(points: np.ndarray, n: int, k: int, rng: np.random.Generator) -> np.ndarray:
    """n of points (P, 3), drawn without replacement with weight 1 / (mean distance to k nearest)."""
    if n > len(points):
        raise ValueError(f"cannot resample {n} points from {len(points)}")
    d = cKDTree(points).query(points, k=k + 1)[0][:, 1:]  # (P, k), self excluded
    w = 1.0 / np.maximum(d.mean(axis=1), 1e-9)
    return points[rng.choice(len(points), size=n, replace=False, p=w / w.sum())]


def build_template(anchor: str, anchor_mesh, demos: list[dict], query: str = "ibs", feature: str = "nif",
                   n_points: int = 500, weights: str | Path | None = None, seed: int = 0) -> Template:
    """A NIT from demos, each {"cloud": (N, 3), "T_frame_anchor": (4, 4), "name": str}.

    `weights`: the field to use (default: the shipped field the feature comes from)."""
    if feature not in FEATURES:
        raise ValueError(f"unknown feature {feature!r}; choose one of {', '.join(FEATURES)}")
    if not demos:
        raise ValueError("a template needs at least one demo")
    weights = weights or FEATURES[feature]
    field = load_field(weights)
    rng = np.random.default_rng(seed)
    per_demo = [query_points(query, anchor_mesh, d["T_frame_anchor"], d["cloud"], n_points, seed + i)
                for i, d in enumerate(demos)]
    points = per_demo[0] if len(demos) == 1 else density_resample(np.concatenate(per_demo), n_points, len(demos), rng)
    distances = np.maximum(signed_distance(scene_of(anchor_mesh), points), 0.0)  # (M,)
    per_demo = demo_features(points, demos, field, feature)  # (D, M, F)
    return Template(points, per_demo.mean(axis=0), anchor, query, feature, field_id(weights),
                    [d.get("name", "") for d in demos], distances.astype(np.float32), per_demo)


def demo_features(points: np.ndarray, demos: list[dict], field: NeuralField, feature: str) -> np.ndarray:
    """Features (D, M, F) of template points (M, 3), anchor frame, in each demo's field (demos as in
    `build_template`)."""
    feats = []
    with torch.no_grad():
        for d in demos:
            x = transform_points(d["T_frame_anchor"], points)[None]  # (1, M, 3) demo frame
            feats.append(point_features(field, feature, field.encode(d["cloud"]), x)[0].numpy())
    return np.stack(feats).astype(np.float32)


def with_demo_features(t: Template, demos: list[dict], weights: str | Path | None = None) -> Template:
    """The template with each demo's own features (`Template.per_demo`), computed from the demos it was
    built from (files keep only their mean: the per-demo ones are 10x the size; one encoding per demo,
    ~0.2 s each on a CPU)."""
    names = [d.get("name", "") for d in demos]
    if names != t.demos:
        raise ValueError(f"the template was built from demos {t.demos}, not {names}: rebuild it")
    weights = weights or FEATURES[t.feature]
    return replace(t, per_demo=demo_features(t.points, demos, load_field(weights), t.feature))


def save_template(t: Template, path: str | Path) -> Path:
    """Write a NIT atomically: an .npz with the arrays and a JSON header (format nift-nit/2)."""
    if t.distances is None:
        raise ValueError("a template to save needs its points' distances to the anchor")
    header = {"format": FORMAT, "anchor": t.anchor, "query": t.query, "feature": t.feature,
              "field": t.field_id, "demos": t.demos}
    return write_npz(path, {"points": t.points.astype(np.float32), "features": t.features.astype(np.float32),
                            "distances": np.asarray(t.distances, np.float32)}, header)


def load_template(path: str | Path, weights: str | Path | None = None) -> Template:
    """Read a NIT; refuse missing, corrupt and wrong-version files, and ones built with other
    weights than `weights` (default: the shipped field of its feature kind)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no template at {path}")
    try:
        header, arrays = read_npz(path, FORMAT, "NIT", ("points", "features", "distances"))
    except WrongFormat as exc:
        if exc.found in OLDER_FORMATS:
            raise StaleTemplate(f"{exc}; rebuild it from its demos") from None
        raise
    missing = [k for k in HEADER_KEYS if not isinstance(header.get(k), (str, list))]
    if missing:
        raise ValueError(f"{path}: the template header lacks {', '.join(missing)}; rebuild it from its demos")
    if header["feature"] not in FEATURES or header["query"] not in QUERIES:
        raise ValueError(f"{path}: unknown template kind {header['query']!r}-{header['feature']!r}")
    points, features, distances = arrays["points"], arrays["features"], arrays["distances"]
    if points.shape[0] != features.shape[0] or points.shape[1:] != (3,) or distances.shape != points.shape[:1]:
        raise ValueError(f"{path}: points {points.shape}, features {features.shape} and distances "
                         f"{distances.shape} do not match")
    t = Template(points.astype(np.float64), features, header["anchor"], header["query"], header["feature"],
                 header["field"], header["demos"], distances.astype(np.float64))
    current = field_id(weights or FEATURES[t.feature])
    if current != t.field_id:
        raise StaleTemplate(f"{path} was built with field {t.field_id}, not with {current}; rebuild it from its demos")
    return t
