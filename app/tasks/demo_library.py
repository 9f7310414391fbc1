"""The demo and template library: a task's demos on disk and the templates built from them.

Layout of a task's directory (`demos/<task>/`): demo-NN.npz (nift-demo/1), and
{grasp,place}-<query>-<feature>.nit.npz (nift-nit/1) - the shipped ones are ibs-nif, NIFT's own.
Templates are rebuilt from the demos when missing, stale, or built with other field weights.
Those the project does not ship (the baselines') are built in the user's cache, never in `demos/`.
"""
from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

from app.io_utils import cache_root
from app.nift.template import (StaleTemplate, Template, build_template, field_id, field_override, load_template,
                               save_template, with_demo_features)
from app.tasks.anchors import anchor_mesh
from app.tasks.demo import DEMO_GLOB, DEMOS_DIR, Demo, load_demo
from app.tasks.task import Task
from app.tasks.staging import leftovers

STAGES = ("grasp", "place")


def task_demos(out: Path) -> list[Demo]:
    """Every demo in a task directory, in name order."""
    paths = sorted(out.glob(DEMO_GLOB))
    if not paths:
        _, old = leftovers(out)
        if old and not out.exists():
            raise FileNotFoundError(f"no demos in {out}: an interrupted `nift teach` left them in {old[-1]}; "
                                    f"the next `nift teach` puts them back (or rename it to {out.name})")
        raise FileNotFoundError(f"no demos in {out}: record some with `nift teach`")
    return [load_demo(p) for p in paths]


def check_demos_task(t: Task, demos: list[Demo]) -> None:
    """Refuse demos recorded for another task than the one whose demos `t` imitates (`Task.demos`)."""
    for d in demos:
        if d.task != t.demos:
            raise ValueError(f"demo {d.name or '?'} ({d.category}) is of task {d.task!r}, not {t.demos!r}: "
                             f"it does not belong in the {t.demos} demos")


def template_path(out: Path, stage: str, query: str = "ibs", feature: str = "nif", nif: str | Path | None = None) -> Path:
    """Where a task's template lives; templates built with other field weights than the shipped ones
    (`nif`: see `field_override`) carry the weights' hash in the name, so several sit side by side."""
    weights = field_override(feature, nif)
    tag = "" if weights is None else f".{field_id(weights).split(':')[1]}"
    return out / f"{stage}-{query}-{feature}{tag}.nit.npz"


def build_task_templates(t: Task, demos: list[Demo], query: str = "ibs", feature: str = "nif",
                         n_points: int = 500, seed: int = 0, nif: str | Path | None = None) -> dict[str, Template]:
    """The grasp and place templates of a task from its demos (`nif`: NIF weights, default shipped);
    a one-line error when a demo is of another task (a bowl's demo in the mug's folder)."""
    check_demos_task(t, demos)
    weights = field_override(feature, nif)
    return {stage: build_template(stage_anchor(t, stage), anchor_mesh(stage_anchor(t, stage)), template_frames(demos, stage),
                                  query, feature, n_points, weights=weights, seed=seed) for stage in STAGES}


def stage_anchor(t: Task, stage: str) -> str:
    """The anchor of a stage's template: the gripper for the grasp, the task's fixture for the place."""
    return "gripper" if stage == "grasp" else t.fixture


def template_frames(demos: list[Demo], stage: str) -> list[dict]:
    """The demos as `build_template` takes them for a stage: cloud, name and the anchor's pose."""
    return [{"cloud": d.cloud, "name": d.name,
             "T_frame_anchor": d.grasp_anchor() if stage == "grasp" else d.place_anchor()} for d in demos]


@lru_cache(maxsize=8)
def _with_demo_features(path: Path, stamp: int, directory: Path, stage: str, weights: str | Path | None) -> Template:
    """A saved template with its demos' own features, once per process and file version (`stamp`):
    they take one encoding per demo (~0.2 s each on a CPU) and are not saved."""
    return with_demo_features(load_template(path, weights), template_frames(task_demos(directory), stage), weights)


def shipped(directory: Path) -> bool:
    """Whether a task directory is one of the project's own (`demos/<task>/`), which runs only read."""
    directory = Path(directory).resolve()
    return directory.parent == DEMOS_DIR.resolve() and not directory.name.startswith(".")


def built_elsewhere(directory: Path) -> Path:
    """Where templates the project does not ship are built for its demos: the user's cache, under
    the digest of the demo files (new demos, new folder)."""
    digest = hashlib.sha1()
    for path in sorted(Path(directory).glob(DEMO_GLOB)):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return cache_root() / "templates" / f"{Path(directory).name}-{digest.hexdigest()[:12]}"


def task_templates(t: Task, directory: Path | None = None, query: str = "ibs", feature: str = "nif",
                   rebuild: bool = False, nif: str | Path | None = None,
                   per_demo: tuple[str, ...] = ()) -> dict[str, Template]:
    """A task's templates from its directory, built from the demos (and saved) when missing, built
    with other field weights, or asked; those of the stages `per_demo` with each demo's own features
    (`Template.per_demo`)."""
    directory = directory or DEMOS_DIR / t.demos
    weights = field_override(feature, nif)
    paths = {s: template_path(directory, s, query, feature, nif) for s in STAGES}
    if not rebuild and not all(p.is_file() for p in paths.values()) and shipped(directory):
        paths = {s: template_path(built_elsewhere(directory), s, query, feature, nif) for s in STAGES}
    if not rebuild and all(p.is_file() for p in paths.values()):
        try:
            templates = {s: load_template(p, weights) for s, p in paths.items()}
        except StaleTemplate:  # the weights changed since: the demos are the source, rebuild
            pass
        else:
            for s in per_demo:
                templates[s] = _with_demo_features(paths[s], paths[s].stat().st_mtime_ns, directory, s, weights)
            return templates
    templates = build_task_templates(t, task_demos(directory), query, feature, nif=nif)
    for stage, template in templates.items():
        save_template(template, paths[stage])
    return templates
