"""Object families: the kinds of shape each category's generator makes, and which seeds make which.

A family is a set of options for a category's builder ("oval body, screw cap"). The seed ranges
are disjoint, and the older two are unchanged, so every published figure stays reproducible:

| split       | seeds             | families                                                        |
|-------------|-------------------|-----------------------------------------------------------------|
| train       | 0 - 4,999         | classic only (the fields shipped today were trained on these)  |
| test        | 100,000 - 100,199 | classic only (Table I, `bench-jobs`)                            |
| wide-train  | 10,000 - 19,999   | every family that is not held out, drawn by seed               |
| wide-test   | 200,000 - 200,199 | every family, held-out ones included, in turn (seed mod count) |

A held-out family never appears in a training split (`tests/test_object_families.py` checks the
`make-data` manifest), so `wide-test` measures generalisation to kinds of shape never trained on.
"""
from __future__ import annotations

import zlib
from dataclasses import dataclass

from app.categories import SPLIT_NAMES

TRAIN_SEEDS = range(0, 5000)
TEST_SEEDS = range(100_000, 100_200)
WIDE_TRAIN_SEEDS = range(10_000, 20_000)
WIDE_TEST_SEEDS = range(200_000, 200_200)
SPLITS = {"train": TRAIN_SEEDS, "test": TEST_SEEDS, "wide-train": WIDE_TRAIN_SEEDS, "wide-test": WIDE_TEST_SEEDS}
assert tuple(SPLITS) == SPLIT_NAMES, "app/categories.py names the splits the CLI offers"
TRAINING_SPLITS = ("train", "wide-train")
CLASSIC = "classic"


@dataclass(frozen=True)
class Family:
    """One kind of shape of a category: its name, whether training never sees it, and what it says."""

    name: str
    held_out: bool
    about: str


FAMILIES: dict[str, tuple[Family, ...]] = {
    "mug": (
        Family(CLASSIC, False, "tapered cup, round C handle (today's mugs)"),
        Family("small-hole", False, "handle hole down to the 18 mm clear opening the peg still passes"),
        Family("large-hole", False, "wide, tall handle hole, set high or low"),
        Family("flat-handle", False, "flat strap handle (wide along the hole's axis, thin across it)"),
        Family("flared-bumpy", True, "flared walls, thick handle, scan-like bumps on the surface"),
    ),
    "bowl": (
        Family(CLASSIC, False, "rounded bowl on a plain foot (today's bowls)"),
        Family("footed", False, "a foot ring under a rounded bowl, shallow to deep"),
        Family("flared-rim", True, "a rim that flares outwards, shallow to deep"),
    ),
    "bottle": (
        Family(CLASSIC, False, "round body, cosine shoulder, straight neck with a lip (today's bottles)"),
        Family("oval", False, "oval body, shoulders of several shapes, screw cap wider than the neck"),
        Family("rounded-rect", False, "rounded-rectangle body, screw cap wider than the neck"),
        Family("grip-handle", False, "round or oval body with an integrated grip handle, screw cap"),
        Family("tapered-cap", True, "round or oval body, a cap that tapers towards the top with no lip"),
        Family("flat-pump", True, "flattened body with a pump top"),
    ),
    "vase": (Family(CLASSIC, False, "free profile of revolution, 0-2 handles"),),
}


def families(category: str, held_out: bool | None = None) -> tuple[Family, ...]:
    """The category's families; only the held-out (True) or only the trained (False) ones if asked."""
    return tuple(f for f in FAMILIES[category] if held_out is None or f.held_out == held_out)


def family_of(category: str, seed: int) -> str:
    """The family a seed of the category makes (see the module's table); classic outside the wide splits."""
    if seed in WIDE_TRAIN_SEEDS:
        trained = families(category, held_out=False)
        return trained[zlib.crc32(f"{category}:{seed}".encode()) % len(trained)].name
    if seed in WIDE_TEST_SEEDS:
        every = families(category)
        return every[(seed - WIDE_TEST_SEEDS.start) % len(every)].name
    return CLASSIC


def is_held_out(category: str, family: str) -> bool:
    """Whether training never sees this family."""
    return any(f.name == family and f.held_out for f in FAMILIES[category])
