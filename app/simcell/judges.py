"""Success judges of the benchmark (NDF's protocol, docs/benchmark.md), with the thresholds named.

Both judges consume the scene: they move the object. Run them on a freshly spawned object.

- grasp: a free-floating gripper appears at the predicted pose and closes on the object, which is
  held in place meanwhile (so the fingers cannot push it away); then object-table collisions
  (and gripper-table, gripper-arm) are off and the object is released; the gripper lifts
  LIFT_HEIGHT in LIFT_TIME and holds HOLD_TIME: success if both fingers still touch the object
  (it may have swung in the grasp; it has not dropped).
- place: the object is set at the predicted pose, released, object-table collisions off, and
  simulated PLACE_TIME: success if it rests (slower than REST_SPEED) touching the rack/shelf,
  not the floor or the table, and - on the shelf - stands within UPRIGHT_TOLERANCE_DEG of upright,
  or - on the rack - hangs (no contact lower than HANG_HEIGHT: a mug on the rack's foot is a miss).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from app.simcell.spawn import SpawnedObject, hold, release, spawn
from hardware.bullet import p
from hardware.gripper_geometry import GripperGeometry
from hardware.sim.floating_gripper import FloatingGripper
from hardware.sim.gripper import SimGripper, SimGripperConfig
from hardware.sim.world import SimWorld

GRASP_FORCE = 40.0  # N
LIFT_HEIGHT = 0.15  # m
LIFT_TIME = 1.0  # s
HOLD_TIME = 0.5  # s
TOUCH_DISTANCE = 0.002  # m: a finger this close to the object still holds it
PLACE_TIME = 2.0  # s
REST_SPEED = 0.05  # m/s
UPRIGHT_TOLERANCE_DEG = 30.0
HANG_HEIGHT = 0.05  # m: on the rack, every contact must be this far above its foot (hanging, not standing)


@dataclass(frozen=True)
class Verdict:
    """A judge's answer and why."""

    success: bool
    reason: str


def _set_collision(world: SimWorld, a: int, b: int, enabled: bool) -> None:
    """Switch collisions between every link pair of bodies a and b.

    PyBullet keeps such pairs by body id even after a body is removed and its id reused, so every
    judge switches back on what it switched off.
    """
    cid = world.require()
    for la in range(-1, p.getNumJoints(a, physicsClientId=cid)):
        for lb in range(-1, p.getNumJoints(b, physicsClientId=cid)):
            p.setCollisionFilterPair(a, b, la, lb, int(enabled), physicsClientId=cid)


def judged_copy(world: SimWorld, obj: SpawnedObject, T_world_obj: np.ndarray,
                judge: Callable[[SpawnedObject], Verdict], pose: str = "upright") -> Verdict:
    """A judge's verdict on a fresh copy of `obj` (same instance or imported object, same scale) at
    T_world_obj, removed again afterwards: the judges consume the scene they are given."""
    copy = spawn(world, obj.category, obj.seed, pose, scale=obj.scale, T_world_obj=T_world_obj, source=obj.source)
    try:
        return judge(copy)
    finally:
        world.remove(copy.body)


def judge_grasp(world: SimWorld, obj: SpawnedObject, T_world_tcp: np.ndarray, avoid: tuple[int, ...] = ()) -> Verdict:
    """Close a floating gripper at T_world_tcp on the object and lift it."""
    geometry = GripperGeometry()
    T_world_tool0 = T_world_tcp @ np.linalg.inv(geometry.T_tool0_tcp)
    holder = FloatingGripper(world, T_world_tool0, geometry)
    holder.load()
    others = (world.table, world.floor, *avoid)
    for other in others:
        _set_collision(world, holder.body, other, False)
    gripper = SimGripper(SimGripperConfig(), holder)
    hold(world, obj)  # the object stays put while the fingers close, as in NDF's teleported grasp
    try:
        gripper.connect()
        if not gripper.close(GRASP_FORCE):
            return Verdict(False, "gripper closed on nothing")
        release(world, obj)
        _set_collision(world, obj.body, world.table, False)  # only now: a free object would fall through
        z0 = world.pose(obj.body)[2, 3]
        dt = world.config.time_step
        steps = int(LIFT_TIME / dt)
        for i in range(1, steps + 1):
            T = T_world_tool0.copy()
            T[2, 3] += LIFT_HEIGHT * i / steps
            holder.move_to(T)
            world.step()
        world.step(int(HOLD_TIME / dt))
        rise = world.pose(obj.body)[2, 3] - z0
        cid = world.require()
        touching = [len(p.getClosestPoints(holder.body, obj.body, TOUCH_DISTANCE, linkIndexA=link,
                                           physicsClientId=cid)) > 0 for link in holder.finger_links]
        if not all(touching):
            return Verdict(False, f"object slipped out of the fingers (moved {rise * 100:+.1f} cm)")
        return Verdict(True, f"held between both fingers after the lift (moved {rise * 100:+.1f} cm)")
    finally:
        for other in others:
            _set_collision(world, holder.body, other, True)
        _set_collision(world, obj.body, world.table, True)
        holder.remove()


def judge_place(world: SimWorld, obj: SpawnedObject, T_world_obj: np.ndarray, fixture_body: int,
                upright: bool) -> Verdict:
    """Set the object at T_world_obj, let go, and see whether it rests on the fixture."""
    release(world, obj)
    _set_collision(world, obj.body, world.table, False)
    world.set_pose(obj.body, T_world_obj)
    try:
        world.step(int(PLACE_TIME / world.config.time_step))
        return resting_verdict(world, obj, fixture_body, upright)
    finally:
        _set_collision(world, obj.body, world.table, True)


def resting_verdict(world: SimWorld, obj: SpawnedObject, fixture_body: int, upright: bool) -> Verdict:
    """Where the object ended up after the place judge's simulation."""
    cid = world.require()
    speed = np.linalg.norm(p.getBaseVelocity(obj.body, physicsClientId=cid)[0])
    if world.in_contact(obj.body, world.floor) or world.pose(obj.body)[2, 3] < -0.2:
        return Verdict(False, "object fell to the floor")
    if not world.in_contact(obj.body, fixture_body):
        return Verdict(False, "object does not touch the fixture")
    if world.in_contact(obj.body, world.table):
        return Verdict(False, "object rests on the table")
    if not upright:
        lowest = min(c[5][2] for c in p.getContactPoints(obj.body, fixture_body, physicsClientId=cid))
        if lowest - world.pose(fixture_body)[2, 3] < HANG_HEIGHT:
            return Verdict(False, f"object is not hanging (touches the rack {100 * lowest:.1f} cm above the table)")
    if speed > REST_SPEED:
        return Verdict(False, f"object still moving ({speed:.2f} m/s)")
    if upright:
        tilt = np.degrees(np.arccos(np.clip(world.pose(obj.body)[2, 2], -1, 1)))
        if tilt > UPRIGHT_TOLERANCE_DEG:
            return Verdict(False, f"object rests tilted by {tilt:.0f} degrees")
    return Verdict(True, "resting on the fixture")
