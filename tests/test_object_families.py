"""Object families: every family builds a watertight solid, the old splits are unchanged, and a
held-out family never reaches a training split or the make-data manifest."""
from __future__ import annotations

import json

import numpy as np
import pytest

from app.objects import generate, semantics, split
from app.objects.families import (CLASSIC, FAMILIES, TRAINING_SPLITS, WIDE_TEST_SEEDS, families, family_of,
                                  is_held_out)
from app.training.data import DataConfig, make_dataset, plan


@pytest.mark.parametrize("category", ["mug", "bowl", "bottle"])
def test_every_family_builds_a_solid_whose_landmarks_match_it(category):
    seeds = {family_of(category, s): s for s in WIDE_TEST_SEEDS}
    assert set(seeds) == {f.name for f in FAMILIES[category]}, "wide-test shows every family"
    for family, seed in seeds.items():
        mesh = generate(category, seed)
        sem = semantics(mesh)
        assert mesh.metadata["family"] == family and mesh.is_watertight and mesh.volume > 0, family
        assert np.isclose(mesh.extents[2], sem.height, atol=1e-3), (family, mesh.extents[2], sem.height)
        assert np.isclose(mesh.bounds[0, 2], 0.0, atol=1e-3), family


def test_the_old_splits_are_classic_and_the_splits_are_disjoint():
    for category in ("mug", "bowl", "bottle"):
        assert {family_of(category, s) for s in split(category, "train")[:200] + split(category, "test")} == {CLASSIC}
    seen = [set(split("mug", name)) for name in ("train", "test", "wide-train", "wide-test")]
    assert sum(len(s) for s in seen) == len(set().union(*seen))


@pytest.mark.parametrize("category", ["mug", "bowl", "bottle"])
def test_a_held_out_family_never_appears_in_a_training_split(category):
    held_out = {f.name for f in families(category, held_out=True)}
    assert held_out, f"{category} holds a family out"
    for name in TRAINING_SPLITS:
        assert not held_out & {family_of(category, s) for s in split(category, name)}
    assert held_out <= {family_of(category, s) for s in split(category, "wide-test")}


def test_the_make_data_manifest_names_no_held_out_family(tmp_path):
    cfg = DataConfig(split="wide-train", instances=4, views=1, queries=50, points=64, shard_instances=6)
    names = {f"{c}/{family_of(c, s)}" for shard in plan(cfg) for c, s in shard}
    assert len(names) > 3, "the wide training split mixes families"
    make_dataset(cfg, tmp_path / "data", workers=1, progress=False)
    manifest = json.loads((tmp_path / "data" / "manifest.json").read_text())
    written = {f for shard in manifest["shards"] for f in shard["families"]}
    assert written == names
    assert not any(is_held_out(*f.split("/")) for f in written)
