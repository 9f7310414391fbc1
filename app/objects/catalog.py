"""The category catalogue: `generate(category, seed)`, seed splits and families (`app.objects.families`),
semantics lookup."""
from __future__ import annotations

import zlib
from functools import lru_cache
from typing import Callable

import numpy as np
import trimesh

from app.categories import CATEGORIES, IN_DOMAIN  # noqa: F401 (IN_DOMAIN: re-exported by app.objects)
from app.objects import bottle, bowl, mug, vase
from app.objects.families import SPLITS, TEST_SEEDS, TRAIN_SEEDS, family_of  # noqa: F401 (seed ranges: re-exported)
from app.objects.semantics import Semantics

Builder = Callable[[int, np.random.Generator, str], tuple[trimesh.Trimesh, Semantics]]  # seed, rng, family
BUILDERS: dict[str, Builder] = {"mug": mug.build, "bowl": bowl.build, "bottle": bottle.build, "vase": vase.build}
RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "mug": mug.RANGES, "bowl": bowl.RANGES, "bottle": bottle.RANGES, "vase": vase.RANGES,
}
assert tuple(BUILDERS) == CATEGORIES, "app/categories.py lists the categories BUILDERS builds"


def check_category(category: str) -> str:
    """Return category if known, else raise a one-line ValueError listing the known ones."""
    if category not in BUILDERS:
        raise ValueError(f"unknown object category {category!r}; choose one of {', '.join(CATEGORIES)}")
    return category


def split(category: str, part: str) -> list[int]:
    """Seeds of a split's instances of a category (`app.objects.families`: the splits never overlap)."""
    check_category(category)
    if part not in SPLITS:
        raise ValueError(f"unknown split {part!r}; choose one of {', '.join(SPLITS)}")
    return list(SPLITS[part])


def _rng(category: str, seed: int) -> np.random.Generator:
    """Generator seeded by (category, seed), so seed 7 of 'mug' and of 'bowl' are unrelated."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), zlib.crc32(category.encode())]))


@lru_cache(maxsize=256)
def _build(category: str, seed: int) -> tuple[trimesh.Trimesh, Semantics]:
    return BUILDERS[category](seed, _rng(category, seed), family_of(category, seed))


def generate(category: str, seed: int) -> trimesh.Trimesh:
    """A watertight instance in its canonical frame; `semantics(mesh)` gives its landmarks.

    Deterministic per (category, seed). The returned mesh is a fresh copy: transform it freely.
    """
    check_category(category)
    if int(seed) != seed or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    mesh, sem = _build(category, int(seed))
    out = mesh.copy()
    out.metadata["semantics"] = sem
    out.metadata["name"] = f"{category}-{seed}"
    out.metadata["family"] = family_of(category, int(seed))
    return out


def semantics(mesh: trimesh.Trimesh) -> Semantics:
    """The semantic landmarks of a mesh made by `generate` (canonical frame)."""
    sem = mesh.metadata.get("semantics")
    if mesh.metadata.get("imported"):
        name = mesh.metadata.get("name", "it")
        raise ValueError(f"the scripted teacher needs a procedural object's landmarks and {name!r} is imported; "
                         f"teach it yourself (nift teach --web --object {name})")
    if not isinstance(sem, Semantics):
        raise ValueError("this mesh has no semantics: only meshes from app.objects.generate carry them")
    return sem
