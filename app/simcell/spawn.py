"""Putting procedural objects into the simulated cell, as the benchmark protocol needs them.

Upright: a random yaw and a position in the workspace, resting on the table. Arbitrary: a Haar
random rotation, lowest point 5 mm above the table, held by a fixed constraint while observed
(as NDF does) until `release` is called. Resting: a Haar random rotation, dropped from DROP_HEIGHT
and left to settle, as an object on a real table lies (a mug on its side, a bowl upside down).
Scale is uniform. Masses are per category (documented below) times scale^3; the collision model is
the CoACD decomposition of the unscaled instance, scaled by PyBullet (uniform scaling keeps convex
parts convex). An imported object (`app.objects.library`) is spawned from its own mesh and stored
collision model; its `seed` only seeds the pose.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from app.categories import POSES
from app.objects import generate
from app.objects.collision import collision_model, visual_model
from app.objects.library import LibraryObject
from app.simcell.cell import WORKSPACE
from hardware.bullet import p, pose_to_pybullet
from hardware.se3 import make_pose, random_rotations, rotvec_to_matrix
from hardware.sim.world import SimWorld

MASS = {"mug": 0.30, "bowl": 0.30, "bottle": 0.45, "vase": 0.50}  # kg at scale 1
DROP_HEIGHT = 0.03  # m: a resting object's lowest point when it is let go
SETTLED_SPEED = (0.005, 0.05)  # m/s and rad/s below which a dropped object counts as settled
SETTLE_TIME = 5.0  # s of simulated time at most for it to settle
SCALE_RANGE = (0.85, 1.15)  # uniform random scaling of test objects


@dataclass
class SpawnedObject:
    """An object in the world: its body, its canonical mesh and scale, and a holding constraint."""

    body: int
    category: str
    seed: int
    mesh: trimesh.Trimesh  # canonical frame, already scaled
    scale: float
    constraint: int | None = None
    source: LibraryObject | None = None  # an imported object; None: the procedural (category, seed)

    @property
    def label(self) -> str:
        """How the object is named in records: its library name, or category-seed."""
        return self.source.name if self.source else f"{self.category}-{self.seed}"


def sample_pose(mesh: trimesh.Trimesh, pose: str, rng: np.random.Generator) -> np.ndarray:
    """T_world_obj for an upright, arbitrary or resting (drop) placement in the workspace (mesh scaled)."""
    if pose not in POSES:
        raise ValueError(f"unknown pose setting {pose!r}; choose {' or '.join(POSES)}")
    (x0, x1), (y0, y1) = WORKSPACE
    R = rotvec_to_matrix([0, 0, rng.uniform(-np.pi, np.pi)]) if pose == "upright" else random_rotations(1, rng)[0]
    xy = [rng.uniform(x0, x1), rng.uniform(y0, y1)]
    rotated = mesh.vertices @ R.T
    z = -rotated[:, 2].min() + {"upright": 0.0, "arbitrary": 0.005, "resting": DROP_HEIGHT}[pose]
    T = make_pose(R, [*xy, z])
    T[:2, 3] -= rotated.mean(axis=0)[:2]  # centre the object, not its canonical origin, on the sample
    return T


def spawn(world: SimWorld, category: str, seed: int, pose: str = "upright", scale: float = 1.0,
          rng: np.random.Generator | None = None, T_world_obj: np.ndarray | None = None,
          source: LibraryObject | None = None) -> SpawnedObject:
    """Add an instance (or the imported `source`) to the world (at T_world_obj, or a sampled pose) and
    let it settle if free."""
    rng = rng or np.random.default_rng(seed)
    if source is not None and source.category != category:  # the message `object_info` gives on load
        raise ValueError(f"object {source.name!r} is a {source.category}, not a {category}")
    canonical = source.mesh if source else generate(category, seed)
    mesh = canonical.copy()
    mesh.apply_scale(scale)
    T = sample_pose(mesh, pose, rng) if T_world_obj is None else T_world_obj
    collision = source.collision if source else collision_model(canonical)
    body = world.add_mesh(visual_model(canonical), collision, T, mass=MASS[category] * scale ** 3,
                          scale=scale, rgba=(0.35, 0.55, 0.85, 1.0))
    obj = SpawnedObject(body, category, seed, mesh, scale, source=source)
    if pose == "arbitrary":
        hold(world, obj)
    world.step(60)  # settle on the table (held objects stay put)
    if pose == "resting":
        settle(world, obj)
    return obj


def settle(world: SimWorld, obj: SpawnedObject, check_every: int = 24) -> bool:
    """Step until the object moves slower than SETTLED_SPEED on two checks in a row (or SETTLE_TIME
    has passed); whether it settled."""
    calm = 0
    for _ in range(int(SETTLE_TIME / (world.config.time_step * check_every))):
        world.step(check_every)
        v, w = p.getBaseVelocity(obj.body, physicsClientId=world.require())
        calm = calm + 1 if np.linalg.norm(v) < SETTLED_SPEED[0] and np.linalg.norm(w) < SETTLED_SPEED[1] else 0
        if calm == 2:
            return True
    return False


def hold(world: SimWorld, obj: SpawnedObject) -> None:
    """Fix the object where it is now (a fixed constraint to the world)."""
    if obj.constraint is None:
        pos, quat = pose_to_pybullet(world.pose(obj.body))
        obj.constraint = p.createConstraint(obj.body, -1, -1, -1, p.JOINT_FIXED, [0, 0, 0], [0, 0, 0], pos,
                                            [0, 0, 0, 1], quat, physicsClientId=world.require())


def release(world: SimWorld, obj: SpawnedObject) -> None:
    """Remove the constraint that holds an arbitrary-pose object."""
    if obj.constraint is not None:
        p.removeConstraint(obj.constraint, physicsClientId=world.require())
        obj.constraint = None
