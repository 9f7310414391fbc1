"""Procedural object categories (mug, bowl, bottle, vase), fixtures (rack, shelf), collision models
and bring-your-own meshes.

    from app.objects import generate, semantics, split
    mug = generate("mug", seed=3)            # watertight trimesh, canonical frame
    semantics(mug).handle_center             # landmarks for teachers and judges
    split("mug", "test")                     # seeds never used for training
"""
from app.objects.catalog import CATEGORIES, IN_DOMAIN, RANGES, check_category, generate, semantics, split
from app.objects.collision import collision_model, decompose
from app.objects.fixtures import Fixture, fixture, rack, shelf
from app.objects.loading import load_mesh
from app.objects.semantics import Semantics

__all__ = [
    "CATEGORIES", "IN_DOMAIN", "RANGES", "check_category", "generate", "semantics", "split",
    "collision_model", "decompose", "Fixture", "fixture", "rack", "shelf", "load_mesh", "Semantics",
]
