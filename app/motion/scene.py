"""The planning scene: a collision model of the cell in its own PyBullet client (DIRECT, no physics).

PyBullet serves here as a collision library only (`hardware.bullet`): the scene never steps
physics and never imports the simulated cell, so it models a real cell just the same.

It holds the robot with its gripper, the table, the rack and the shelf at their configured poses,
and obstacles added at run time (the convex hull of the observed object). `collisions(q)` names
what the arm would hit at joint positions q. It is a model built from the cell's configuration,
as a real cell's planner would have - it never looks at the simulated world the arm moves in.

Inside `holding(name, T_base_tcp)` the named cloud obstacle is carried: a copy of its hull (without
its footprint on the table) moves rigidly with the TCP as it was at T_base_tcp, and `collisions(q)`
also names what it would hit ("held-rack"); the gripper's own links, which hold it, are exempt.
Without it a carried mug was swept through the rack in 2 of 10 executed teacher jobs (our fix for
the protective stops that followed; MoveIt calls this an attached collision object).

A broad phase skips every query whose two bounding boxes (Bullet's, grown by the margin) do not
overlap: the answers stay the same, and a state is checked in about 0.09 ms rather than 0.14 (with
the pose conversion of the carried object no longer SciPy's, a carry's state in half the time).

`gripper_collisions(T_base_tcp)` asks the same of the gripper alone, open, at a TCP pose, without
the arm: a cheap first test of candidate grasp and place poses before any IK (`app.jobs.choice`).
Inside `fingers(width)` both grippers' fingers stand that far apart instead of fully open: closed
on a held object, whose open fingers would reach 4 cm to each side into a rack's post.
"""
from __future__ import annotations

import itertools
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from app.layout import CellLayout, add_fixtures
from hardware.bullet import add_table, connect, convex_shape, joint_and_link_indices, load_cell_robot, p, set_pose
from hardware.gripper_geometry import FINGER_JOINTS, GripperGeometry, standalone_gripper_urdf
from hardware.kinematics import JOINT_NAMES, UR5Kinematics
from hardware.robot_description import HOME_Q, write_cached

HELD = "held"  # the name collisions give the carried object
GRIPPER_LINKS = ("gripper_palm", "finger_left", "finger_right")
ARM_LINKS = ("shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link", "wrist_3_link")
ON_TABLE = ("base_link", "shoulder_link")  # bolted to the table: never checked against it
# Two apart in the chain but close by design: their meshes overlap by 5 mm whenever the upper arm
# points below horizontal, where its elbow is already under the table top (the table check says so).
CLOSE_BY_DESIGN = {("base_link", "upper_arm_link")}


class PlanningScene:
    """Collision queries for joint configurations of the cell's UR5."""

    def __init__(self, layout: CellLayout = CellLayout(), margin: float = 0.005,
                 geometry: GripperGeometry = GripperGeometry()) -> None:
        self._args = (layout, margin, geometry)
        self.layout = layout  # where the fixtures stand
        self.margin = margin  # metres of clearance that count as a collision
        self.geometry = geometry
        self.finger_width = geometry.stroke  # m between the fingers' inner faces (`fingers`)
        self.kinematics = UR5Kinematics(tcp_offset=geometry.T_tool0_tcp)
        self.client: int | None = connect()
        self._shape_files = tempfile.TemporaryDirectory(prefix="nift-scene-")  # cloud obstacles' hulls (OBJ)
        self._shape_dir = Path(self._shape_files.name)
        self.robot = load_cell_robot(self.client, geometry, np.linalg.inv(self.kinematics.T_world_base))
        joints, links = joint_and_link_indices(self.robot, self.client)
        self.arm_joints = [joints[name] for name in JOINT_NAMES]
        self.finger_joints = [joints[name] for name in FINGER_JOINTS]
        self._joints = [*self.arm_joints, *self.finger_joints]  # set together: one call per state
        self.obstacles: dict[str, int] = {"table": add_table(self.client), **add_fixtures(self.client, layout)}
        self.links = {name: links[name] for name in ("base_link", *ARM_LINKS, *GRIPPER_LINKS)}
        self.self_pairs = self._self_pairs()
        names = list(self.links)
        self._off_table = np.array([name not in ON_TABLE for name in names])  # (L,) links checked against the table
        self._arm = np.array([name in ARM_LINKS for name in names])  # (L,) links checked against the held object
        self._pair_index = np.array([[names.index(a), names.index(b)] for a, b in self.self_pairs]).reshape(-1, 2)
        self.solids: dict[str, np.ndarray] = {}  # cloud obstacles' points (with their shadow, no footprint)
        self._shapes: dict[str, int] = {}  # the collision shape of each cloud obstacle
        self._held_shapes: dict[str, int] = {}  # the collision shape of each cloud obstacle when carried
        self.held: tuple[int, np.ndarray] | None = None  # (body, T_tcp_body) while holding
        self._boxes: dict[str, np.ndarray] = {}  # the obstacles' bounding boxes (2, 3), once asked for
        self.ghost = self._load_ghost_gripper()

    def close(self) -> None:
        """Free the collision model's client."""
        if self.client is not None:
            p.disconnect(self.client)
            self.client = None
            self._shape_files.cleanup()

    def rebuild(self) -> None:
        """The same scene in a fresh client, without run-time obstacles: PyBullet never frees a mesh
        shape (a job's object hull), only a whole client (a series of jobs rebuilds now and then)."""
        self.close()
        self.__init__(*self._args)

    def set_q(self, q: np.ndarray) -> None:
        """Put the model arm at q, the fingers `finger_width` apart (fully open unless `fingers` says)."""
        half = self.finger_width / 2
        p.resetJointStatesMultiDof(self.robot, self._joints, [[float(qi)] for qi in q] + [[half], [half]],
                                   physicsClientId=self.client)

    @contextmanager
    def fingers(self, width: float):
        """Within the block the model's fingers (the arm's and the free gripper's) stand `width` apart,
        clipped to the stroke: while an object is held they are closed on it, not fully open."""
        before = self.finger_width
        self.finger_width = float(np.clip(width, 0.0, self.geometry.stroke))
        self._set_ghost_fingers()
        try:
            yield self
        finally:
            self.finger_width = before
            self._set_ghost_fingers()

    def _set_ghost_fingers(self) -> None:
        for joint in self.ghost_fingers:
            p.resetJointState(self.ghost, joint, self.finger_width / 2, 0.0, physicsClientId=self.client)

    def add_cloud(self, name: str, points: np.ndarray, eye: np.ndarray | None = None, depth: float = 0.03) -> None:
        """An obstacle from a single-view cloud (N, 3) in the base frame: the convex hull of the
        points, their shadow `depth` further along the rays from the camera at `eye` (the unseen
        back), and the footprint of both on the table (z = 0)."""
        self.remove(name)
        points = np.asarray(points, float)
        parts = [points]
        if eye is not None:
            rays = points - np.asarray(eye, float)
            parts.append(points + depth * rays / np.linalg.norm(rays, axis=1, keepdims=True))
        solid = np.concatenate(parts)
        self.solids[name] = solid
        footprint = solid * [1.0, 1.0, 0.0]
        self._shapes[name] = convex_shape(self.client, np.concatenate([solid, footprint]), self._shape_dir / f"{name}.obj")
        self.obstacles[name] = p.createMultiBody(0.0, self._shapes[name], physicsClientId=self.client)

    def remove(self, name: str) -> None:
        """Drop a run-time obstacle (no-op if absent) and its hulls' files (Bullet keeps the shapes
        until `rebuild`: its removeCollisionShape frees nothing)."""
        body = self.obstacles.pop(name, None)
        self._boxes.pop(name, None)
        self.solids.pop(name, None)
        if body is not None:
            p.removeBody(body, physicsClientId=self.client)
        for shapes, suffix in ((self._shapes, ""), (self._held_shapes, "-held")):
            if shapes.pop(name, None) is not None:
                (self._shape_dir / f"{name}{suffix}.obj").unlink(missing_ok=True)

    def _load_ghost_gripper(self) -> int:
        """A free copy of the gripper, fingers open, parked far away: `gripper_collisions` moves it."""
        path = write_cached("nift_gripper", standalone_gripper_urdf(self.geometry))
        body = p.loadURDF(str(path), [0.0, 0.0, -10.0], useFixedBase=True, physicsClientId=self.client)
        joints, _ = joint_and_link_indices(body, self.client)
        self.ghost_fingers = [joints[name] for name in FINGER_JOINTS]
        for joint in self.ghost_fingers:
            p.resetJointState(body, joint, self.finger_width / 2, 0.0, physicsClientId=self.client)
        return body

    def gripper_collisions(self, T_base_tcp: np.ndarray, ignore: tuple[str, ...] = ()) -> list[str]:
        """Obstacles (not in `ignore`) the gripper alone (fingers `finger_width` apart) would hit at a TCP
        pose - no arm, no IK."""
        set_pose(self.client, self.ghost, T_base_tcp @ np.linalg.inv(self.geometry.T_tool0_tcp))
        return self._obstacles_near(self.ghost, ignore)

    def _obstacles_near(self, body: int, ignore: tuple[str, ...], box: np.ndarray | None = None) -> list[str]:
        """Obstacles (not in `ignore`) within the margin of a free body (`box`: its box, when known)."""
        names, boxes = self._obstacle_boxes(ignore)
        near = self._overlap(self._box(body) if box is None else box, boxes)  # (O,)
        return [name for name, hit in zip(names, near)
                if hit and p.getClosestPoints(body, self.obstacles[name], self.margin, physicsClientId=self.client)]

    @contextmanager
    def holding(self, name: str, T_base_tcp: np.ndarray):
        """Within the block the cloud obstacle `name` moves with the TCP, grasped at T_base_tcp
        (a no-op for a name that is not a cloud obstacle)."""
        if name not in self.solids:
            yield self
            return
        if name not in self._held_shapes:  # one shape per cloud, however often it is carried in planning
            self._held_shapes[name] = convex_shape(self.client, self.solids[name], self._shape_dir / f"{name}-held.obj")
        body = p.createMultiBody(0.0, self._held_shapes[name], physicsClientId=self.client)
        self.held = (body, np.linalg.inv(T_base_tcp))  # the body's frame is the base frame at the grasp
        try:
            yield self
        finally:
            self.held = None
            p.removeBody(body, physicsClientId=self.client)

    def collisions(self, q: np.ndarray, ignore: tuple[str, ...] = ()) -> list[str]:
        """Names of the contacts ('forearm_link-table', 'wrist_3_link-upper_arm_link', ...) at q, nearer
        than the margin; obstacles named in `ignore` are skipped."""
        return list(self._contacts(q, ignore))

    def is_free(self, q: np.ndarray, ignore: tuple[str, ...] = ()) -> bool:
        """No contact at q (`collisions` is empty), stopping at the first one found: the planner's check."""
        return next(self._contacts(q, ignore), None) is None

    def _contacts(self, q: np.ndarray, ignore: tuple[str, ...]) -> Iterator[str]:
        """The contacts of `collisions`, one at a time: obstacles (one query per obstacle for all the
        robot's links), then the self pairs, then the carried object; each only where the bounding
        boxes say it may be within the margin."""
        self.set_q(q)
        boxes = self._link_boxes()  # (L, 2, 3)
        names, obstacle_boxes = self._obstacle_boxes(ignore)
        reach = self._overlap(boxes[:, None], obstacle_boxes[None])  # (L, O)
        reach &= self._off_table[:, None] | (np.array(names) != "table")[None]
        for obstacle, near_any in zip(names, reach.any(axis=0)):
            if not near_any:
                continue
            near = self._links_near(self.obstacles[obstacle])
            yield from (f"{link}-{obstacle}" for link, index in self.links.items()
                        if index in near and not (obstacle == "table" and link in ON_TABLE))
        for a, b in self._pairs_in_reach(boxes):
            if self._near(self.robot, self.robot, self.links[a], self.links[b]):
                yield f"{a}-{b}"
        yield from self._held_collisions(q, ignore, boxes)

    # The broad phase: Bullet's axis-aligned bounding boxes, grown by the margin. Links whose boxes do
    # not overlap are farther apart than the margin and need no query (the answers stay the same).
    def _link_boxes(self) -> np.ndarray:
        """(L, 2, 3) lower and upper corners of the robot's links' boxes, in `links` order."""
        return np.array([p.getAABB(self.robot, index, physicsClientId=self.client) for index in self.links.values()])

    def _overlap(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether boxes a and b (..., 2, 3), grown by the margin, overlap (...)."""
        return ((a[..., 0, :] <= b[..., 1, :] + self.margin) & (b[..., 0, :] <= a[..., 1, :] + self.margin)).all(axis=-1)

    def _box(self, body: int) -> np.ndarray:
        """(2, 3) the box around all of a body's links."""
        links = range(-1, p.getNumJoints(body, physicsClientId=self.client))
        boxes = np.array([p.getAABB(body, link, physicsClientId=self.client) for link in links])  # (K, 2, 3)
        return np.array([boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)])

    def _obstacle_boxes(self, ignore: tuple[str, ...]) -> tuple[list[str], np.ndarray]:
        """The obstacles not in `ignore` and their boxes (O, 2, 3)."""
        names = [name for name in self.obstacles if name not in ignore]
        for name in names:  # obstacles never move: each box is computed once
            if name not in self._boxes:
                self._boxes[name] = self._box(self.obstacles[name])
        return names, np.array([self._boxes[name] for name in names]).reshape(-1, 2, 3)

    def _pairs_in_reach(self, boxes: np.ndarray) -> list[tuple[str, str]]:
        """The self pairs whose links' boxes overlap (a quarter of them, on average)."""
        overlap = self._overlap(boxes[self._pair_index[:, 0]], boxes[self._pair_index[:, 1]])  # (P,)
        return [pair for pair, near in zip(self.self_pairs, overlap) if near]

    def _held_collisions(self, q: np.ndarray, ignore: tuple[str, ...], boxes: np.ndarray) -> list[str]:
        """What the carried object hits at q: obstacles not ignored, arm links but the gripper's
        (`boxes`: the links' boxes at q)."""
        if self.held is None:
            return []
        body, T_tcp_body = self.held
        set_pose(self.client, body, self.kinematics.fk(q) @ T_tcp_body)
        box = self._box(body)
        found = [f"{HELD}-{name}" for name in self._obstacles_near(body, ignore, box)]
        if not (self._overlap(boxes, box) & self._arm).any():
            return found
        near = self._links_near(body)
        return found + [f"{HELD}-{link}" for link in ARM_LINKS if self.links[link] in near]

    def _links_near(self, body: int) -> set[int]:
        """Indices of the robot's links within the margin of a body: one query for all of them."""
        return {c[3] for c in p.getClosestPoints(self.robot, body, self.margin, physicsClientId=self.client)}

    def _near(self, body_a: int, body_b: int, link_a: int, link_b: int) -> bool:
        return len(p.getClosestPoints(body_a, body_b, self.margin, link_a, link_b, physicsClientId=self.client)) > 0

    def _self_pairs(self) -> list[tuple[str, str]]:
        """Link pairs that can collide: not neighbours in the chain (those touch by design), not both
        gripper parts, not CLOSE_BY_DESIGN, and clear of each other at the home configuration."""
        chain = ["base_link", *ARM_LINKS, "gripper"]
        rank = {name: chain.index("gripper" if name in GRIPPER_LINKS else name) for name in self.links}
        self.set_q(HOME_Q)
        pairs = []
        for a, b in itertools.combinations(self.links, 2):
            if abs(rank[a] - rank[b]) < 2 or (a, b) in CLOSE_BY_DESIGN:
                continue
            if not self._near(self.robot, self.robot, self.links[a], self.links[b]):
                pairs.append((a, b))
        return pairs
