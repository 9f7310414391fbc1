"""PyBullet as a geometry library: the quiet import, pose conversion, bodies, the cell's table and robot.

Both the simulated devices (`hardware.sim`, which step physics) and the planning scene's collision
model (`app.motion.scene`, which never steps) build their bodies with these functions, each in a
PyBullet client of its own. Nothing here simulates: no gravity, no stepping, no motors.

The table is the plane z = 0 of the robot's base frame (UR `base`): the UR5 is bolted to it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
from scipy.spatial import ConvexHull, QhullError
from scipy.spatial.transform import Rotation

from hardware.gripper_geometry import GripperGeometry
from hardware.robot_description import cell_robot_urdf, write_cached

TABLE_SIZE = (1.6, 1.4, 0.05)  # x, y, thickness
TABLE_CENTER_XY = (0.35, 0.0)
TABLE_HEIGHT = 0.75  # table top above the floor


def _import_pybullet_quietly():
    """Import pybullet with fds 1 and 2 pointed at /dev/null: its C module prints a build banner,
    which would spoil one-line errors and piped output. Later imports find it loaded."""
    import ctypes
    import os
    import sys

    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    try:
        import pybullet

        ctypes.CDLL(None).fflush(None)  # whatever C buffered goes to /dev/null too
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, devnull):
            os.close(fd)
    return pybullet


p = _import_pybullet_quietly()  # every module of ours takes pybullet from here: `from hardware.bullet import p`


def connect(gui: bool = False) -> int:
    """A new PyBullet client (DIRECT, or GUI) with deterministic pair order and no file cache.

    PyBullet's file cache (`enableFileCaching`, on by default) keeps every OBJ it has loaded for the
    life of the process - disconnecting the client frees none of it - so a cell meeting a new object
    every job grew about 0.6 MB a file; with it off the same loads stay flat (docs/limits.md, "Soak")."""
    client = p.connect(p.GUI if gui else p.DIRECT)
    p.setPhysicsEngineParameter(deterministicOverlappingPairs=1, enableFileCaching=0, physicsClientId=client)
    return client


def convex_shape(client: int, points: np.ndarray, path: Path) -> int:
    """A convex collision shape: the hull of the points (N, 3), written to the OBJ `path` and loaded.

    PyBullet's `createCollisionShape(vertices=...)` never frees the Python list it is given (about
    5 KB a 50-vertex hull, for the life of the process, whatever is removed or disconnected); a file
    is read and let go. Keep the file while a body uses the shape: a DIRECT client's renderer reads
    it again when a body is made from it."""
    points = np.asarray(points, float)
    try:
        hull = ConvexHull(points)
    except QhullError:  # a flat set: joggled into a thin solid, as Bullet's own hull of it would be
        hull = ConvexHull(points, qhull_options="QJ")
    number = np.zeros(len(points), int)
    number[hull.vertices] = np.arange(1, len(hull.vertices) + 1)  # OBJ counts from 1
    path.write_text("".join(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in points[hull.vertices]) +
                    "".join(f"f {a} {b} {c}\n" for a, b, c in number[hull.simplices]))
    return p.createCollisionShape(p.GEOM_MESH, fileName=str(path), physicsClientId=client)


NEAR_ROTATION = 1e-6  # |R^T R - I| up to which Eigen's conversion, normalised, is used (a float32 pose: ~2e-7)


def pose_to_pybullet(T: np.ndarray) -> tuple[list[float], list[float]]:
    """4x4 pose -> (position, xyzw quaternion) as PyBullet wants them. A rotation, or a matrix within
    NEAR_ROTATION of one, goes through Eigen's conversion, normalised (pinocchio's, 2 us: the planning
    scene poses the carried object at every state it checks; the quaternion is as far from the
    nearest rotation's as the matrix is); a matrix farther off, through SciPy's nearest rotation (50 us)."""
    R = np.ascontiguousarray(T[:3, :3], dtype=np.float64)
    if np.abs(R.T @ R - np.eye(3)).max() < NEAR_ROTATION:
        return T[:3, 3].tolist(), pin.Quaternion(R).normalized().coeffs().tolist()
    return T[:3, 3].tolist(), Rotation.from_matrix(R).as_quat().tolist()


def pybullet_to_pose(position, quaternion) -> np.ndarray:
    """(position, xyzw quaternion) -> 4x4 pose."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_quat(quaternion).as_matrix()
    T[:3, 3] = position
    return T


def joint_and_link_indices(body: int, client: int) -> tuple[dict[str, int], dict[str, int]]:
    """({joint name: index}, {child link name: index}) of a multibody (a link's index is its joint's)."""
    joints, links = {}, {}
    for j in range(p.getNumJoints(body, physicsClientId=client)):
        info = p.getJointInfo(body, j, physicsClientId=client)
        joints[info[1].decode()] = j
        links[info[12].decode()] = j
    return joints, links


def add_box(client: int, size, center, mass: float = 0.0, rgba=(0.6, 0.6, 0.6, 1), friction: float = 0.8) -> int:
    """A box body (static when mass = 0)."""
    half = [s / 2 for s in size]
    col = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=client)
    vis = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=rgba, physicsClientId=client)
    body = p.createMultiBody(mass, col, vis, basePosition=list(center), physicsClientId=client)
    p.changeDynamics(body, -1, lateralFriction=friction, physicsClientId=client)
    return body


def add_mesh(client: int, visual_obj: Path, collision_obj: Path, T_world_body: np.ndarray, mass: float = 0.0,
             scale: float = 1.0, rgba=(0.6, 0.7, 0.9, 1), friction: float = 0.8, margin: float | None = None) -> int:
    """A body from a visual OBJ and a collision OBJ (one convex hull per `o` block); `margin` (m): the
    collision margin of its hulls, which Bullet grows them by (None: Bullet's default, 1 mm)."""
    s = [scale] * 3
    col = p.createCollisionShape(p.GEOM_MESH, fileName=str(collision_obj), meshScale=s, physicsClientId=client)
    vis = p.createVisualShape(p.GEOM_MESH, fileName=str(visual_obj), meshScale=s, rgbaColor=rgba,
                              physicsClientId=client)
    pos, quat = pose_to_pybullet(T_world_body)
    body = p.createMultiBody(mass, col, vis, basePosition=pos, baseOrientation=quat, physicsClientId=client)
    p.changeDynamics(body, -1, lateralFriction=friction, spinningFriction=0.002, rollingFriction=0.0005,
                     physicsClientId=client)
    if margin is not None:
        p.changeDynamics(body, -1, collisionMargin=margin, physicsClientId=client)
    return body


def set_pose(client: int, body: int, T: np.ndarray) -> None:
    """Teleport a body (velocity zeroed)."""
    p.resetBasePositionAndOrientation(body, *pose_to_pybullet(T), physicsClientId=client)
    p.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=client)


def add_table(client: int) -> int:
    """The table the robot stands on: its top is the plane z = 0."""
    sx, sy, sz = TABLE_SIZE
    return add_box(client, (sx, sy, sz), (*TABLE_CENTER_XY, -sz / 2), rgba=(0.75, 0.7, 0.62, 1))


def load_cell_robot(client: int, geometry: GripperGeometry, T_world_root: np.ndarray) -> int:
    """The UR5 with our gripper at tool0 (URDF assembled into the cache), its URDF root at T_world_root."""
    path = write_cached("ur5_nift_gripper", cell_robot_urdf(geometry))
    pos, quat = pose_to_pybullet(T_world_root)
    return p.loadURDF(str(path), pos, quat, useFixedBase=True, flags=p.URDF_USE_SELF_COLLISION_EXCLUDE_PARENT,
                      physicsClientId=client)
