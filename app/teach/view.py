"""The teach page's 3-D scene (viser): the cell as it stands, drawn from the session's state.

    /robot       the UR5 and our gripper from the cell's URDF (viser.extras.ViserUrdf), at the arm's q
    /table /rack /shelf   the cell's furniture at the configured poses
    /object      the object on the table (or in the fingers), /cloud the Kinect's points of it
    /tcp         the freedrive gizmo; /tcp/ghost the open gripper, red where it cannot go
    /predicted   ghost gripper and ghost object of the imitation's grasp and place
    /demo        a saved demo shown again: its cloud, grasp gripper and placed object
"""
from __future__ import annotations

import numpy as np
import trimesh
import viser
import yourdfpy
from viser.extras import ViserUrdf

from app.objects import fixture
from app.tasks.demo import Demo
from hardware.bullet import TABLE_CENTER_XY, TABLE_SIZE
from hardware.gripper_geometry import FINGER_JOINTS, GripperGeometry
from hardware.robot_description import cell_robot_urdf, write_cached
from hardware.se3 import invert
from scipy.spatial.transform import Rotation

CLOUD_COLOUR = (255, 110, 0)  # the Kinect's points: orange (the browser test looks for it)
ROBOT_COLOUR = (0.42, 0.45, 0.75)  # the arm: slate blue
OBJECT_COLOUR, FIXTURE_COLOUR = (70, 175, 120), (125, 118, 110)  # green object, grey-brown rack and shelf
BAD_COLOUR, GHOST_COLOUR = (230, 40, 40), (150, 110, 230)  # refused freedrive red, predictions violet


def wxyz(T: np.ndarray) -> np.ndarray:
    """viser's quaternion (w, x, y, z) of a pose's rotation."""
    x, y, z, w = Rotation.from_matrix(T[:3, :3]).as_quat()
    return np.array([w, x, y, z])


def pose_of(position: np.ndarray, quaternion_wxyz: np.ndarray) -> np.ndarray:
    """(4, 4) from viser's position and (w, x, y, z)."""
    w, x, y, z = quaternion_wxyz
    T = np.eye(4)
    T[:3, :3] = Rotation.from_quat([x, y, z, w]).as_matrix()
    T[:3, 3] = position
    return T


def gripper_mesh(width: float | None = None, geometry: GripperGeometry = GripperGeometry()) -> trimesh.Trimesh:
    """The gripper's palm and fingers as boxes in the TCP frame, the fingers `width` apart (default open)."""
    boxes = geometry.corners(width).reshape(3, 8, 3)
    return trimesh.util.concatenate([trimesh.creation.box(bounds=[b.min(0), b.max(0)]) for b in boxes])


class CellView:
    """Draws a session's cell on a viser server and keeps it current (`update`)."""

    def __init__(self, server: viser.ViserServer, session) -> None:
        self.server, self.session = server, session
        scene = server.scene
        scene.set_up_direction("+z")
        cell = session.cell
        urdf = yourdfpy.URDF.load(str(write_cached("ur5_nift_gripper", cell_robot_urdf())), load_meshes=True,
                                  build_scene_graph=True)
        root = invert(session.scene.kinematics.T_world_base)  # the URDF's root where the base frame is the origin
        scene.add_frame("/robot", show_axes=False, position=root[:3, 3], wxyz=wxyz(root))
        self.robot = ViserUrdf(server, urdf, root_node_name="/robot", mesh_color_override=ROBOT_COLOUR)
        self.joint_names = list(self.robot.get_actuated_joint_names())
        sx, sy, sz = TABLE_SIZE
        scene.add_box("/table", (190, 178, 158), (sx, sy, sz), position=(*TABLE_CENTER_XY, -sz / 2))
        for name in ("rack", "shelf"):
            T = cell.config.fixture_pose(name)
            scene.add_mesh_simple(f"/{name}", fixture(name).mesh.vertices, fixture(name).mesh.faces,
                                  color=FIXTURE_COLOUR, position=T[:3, 3], wxyz=wxyz(T))
        self.gizmo = scene.add_transform_controls("/tcp", scale=0.15, line_width=3.0)
        self.ghost = None
        self.object_name: str | None = None
        self.object_nodes: list = []  # /object and /cloud of the object on the table
        self.ghosts: list = []  # /predicted and /demo nodes
        server.initial_camera.position = (1.45, -0.95, 0.85)
        server.initial_camera.look_at = (0.45, 0.1, 0.1)

    # the live cell -----------------------------------------------------------------------------------
    def update(self, move_gizmo: bool = True) -> None:
        """Arm, fingers, object and cloud as they are now; the gizmo on the TCP unless told not to."""
        s = self.session
        cfg = dict(zip(self.joint_names, np.zeros(len(self.joint_names))))
        cfg.update(zip(("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
                        "wrist_3_joint"), s.q()))
        for joint in FINGER_JOINTS:
            cfg[joint] = s.cell.gripper.width / 2
        self.robot.update_cfg(np.array([cfg[n] for n in self.joint_names]))
        if move_gizmo:
            T = s.tcp()
            self.gizmo.position, self.gizmo.wxyz = T[:3, 3], wxyz(T)
        self.mark(None)
        self._object()

    def mark(self, ok: bool | None, T_base_tcp: np.ndarray | None = None) -> None:
        """The ghost gripper at the gizmo: red where freedrive cannot go, none when it followed."""
        if self.ghost is not None:
            self.ghost.remove()
            self.ghost = None
        if ok is False and T_base_tcp is not None:
            mesh = gripper_mesh()
            self.ghost = self.server.scene.add_mesh_simple(
                "/tcp_refused", mesh.vertices, mesh.faces, color=BAD_COLOUR, opacity=0.6,
                position=T_base_tcp[:3, 3], wxyz=wxyz(T_base_tcp))

    def _object(self) -> None:
        s, scene = self.session, self.server.scene
        current = s.current
        key = None if current is None else id(current)
        if self.object_name != key:
            for node in self.object_nodes:
                node.remove()
            self.object_nodes, self.object_name = [], key
            if current is not None:
                mesh = current.obj.mesh
                self.object_nodes = [scene.add_mesh_simple("/object", mesh.vertices, mesh.faces, color=OBJECT_COLOUR),
                                     scene.add_point_cloud("/cloud", current.cloud.astype(np.float32), CLOUD_COLOUR,
                                                           point_size=0.006)]
        if current is not None:
            T = s.object_pose()
            self.object_nodes[0].position, self.object_nodes[0].wxyz = T[:3, 3], wxyz(T)

    # ghosts -------------------------------------------------------------------------------------------
    def show_prediction(self) -> None:
        """The imitation's grasp (ghost gripper) and place (ghost object and gripper)."""
        s, scene = self.session, self.server.scene
        pred, current = s.prediction, s.current
        gripper = gripper_mesh()
        T_place_obj = pred.motion @ current.T_base_obj
        T_place_tcp = pred.motion @ pred.T_base_tcp
        for name, T, mesh in (("/predicted/grasp", pred.T_base_tcp, gripper),
                              ("/predicted/place_gripper", T_place_tcp, gripper),
                              ("/predicted/place_object", T_place_obj, current.obj.mesh)):
            self.ghosts.append(scene.add_mesh_simple(name, mesh.vertices, mesh.faces, color=GHOST_COLOUR, opacity=0.45,
                                                     position=T[:3, 3], wxyz=wxyz(T)))

    def show_demo(self, demo: Demo, mesh: trimesh.Trimesh | None) -> None:
        """A saved demo again: its cloud, its grasp, and (with its mesh) the object where it was placed."""
        scene = self.server.scene
        self.ghosts.append(scene.add_point_cloud("/demo/cloud", demo.cloud.astype(np.float32), (40, 160, 230),
                                                 point_size=0.006))
        g = gripper_mesh()
        self.ghosts.append(scene.add_mesh_simple("/demo/grasp", g.vertices, g.faces, color=GHOST_COLOUR, opacity=0.45,
                                                 position=demo.T_base_tcp[:3, 3], wxyz=wxyz(demo.T_base_tcp)))
        if mesh is not None:
            T = demo.T_base_fixture @ demo.T_fixture_obj
            self.ghosts.append(scene.add_mesh_simple("/demo/placed", mesh.vertices, mesh.faces, color=GHOST_COLOUR,
                                                     opacity=0.45, position=T[:3, 3], wxyz=wxyz(T)))

    def clear_ghosts(self) -> None:
        for node in self.ghosts:
            node.remove()
        self.ghosts = []
