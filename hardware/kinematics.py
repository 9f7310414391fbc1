"""UR5 kinematics with Pinocchio, from the installed example-robot-data URDF.

Frames: poses are expressed in the UR controller's `base` frame (the URDF's `base` link, which is
`base_link` turned by pi about z) - the frame a real UR reports `getActualTCPPose` in and the world
frame of this application. The TCP is `tool0` composed with a settable offset.

Closed-form IK (`ik_all`: every branch) comes from ur_analytic_ik, whose UR5 `base` -> `tool0`
forward kinematics equals this URDF's (a test checks it).
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import ur_analytic_ik

from hardware.robot_description import ur5_urdf

JOINT_NAMES = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
               "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")


class UR5Kinematics:
    """Forward kinematics, TCP Jacobian and damped-least-squares IK of the UR5."""

    def __init__(self, tcp_offset: np.ndarray | None = None) -> None:
        self.model = pin.buildModelFromUrdf(str(ur5_urdf()))
        self.data = self.model.createData()
        tool0 = self.model.getFrameId("tool0")
        frame = self.model.frames[tool0]
        self._tcp = self.model.addFrame(pin.Frame("tcp", frame.parentJoint, tool0, frame.placement,
                                                  pin.FrameType.OP_FRAME))
        self.data = self.model.createData()
        self._tool0_in_joint = frame.placement
        pin.framesForwardKinematics(self.model, self.data, pin.neutral(self.model))
        self.T_world_base = self.data.oMf[self.model.getFrameId("base")].homogeneous.copy()
        self._base_inv = pin.SE3(self.T_world_base).inverse()
        self.lower = self.model.lowerPositionLimit.copy()
        self.upper = self.model.upperPositionLimit.copy()
        self.velocity_limit = self.model.velocityLimit.copy()
        self.set_tcp(np.eye(4) if tcp_offset is None else tcp_offset)

    def set_tcp(self, T_tool0_tcp: np.ndarray) -> None:
        """Set the TCP as a 4x4 offset from tool0."""
        self.T_tool0_tcp = np.asarray(T_tool0_tcp, dtype=np.float64).copy()
        self.model.frames[self._tcp].placement = self._tool0_in_joint * pin.SE3(self.T_tool0_tcp)

    def _update(self, q: np.ndarray) -> None:
        pin.forwardKinematics(self.model, self.data, np.asarray(q, dtype=np.float64))
        pin.updateFramePlacement(self.model, self.data, self._tcp)

    def fk(self, q: np.ndarray) -> np.ndarray:
        """T_base_tcp (4x4) at joint positions q (6,)."""
        self._update(q)
        return (self._base_inv * self.data.oMf[self._tcp]).homogeneous

    def frame_pose(self, q: np.ndarray, frame: str) -> np.ndarray:
        """T_base_frame (4x4) of any URDF frame at q."""
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=np.float64))
        return (self._base_inv * self.data.oMf[self.model.getFrameId(frame)]).homogeneous

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """TCP Jacobian (6, 6) in the TCP's own frame (twist = J qd)."""
        pin.computeJointJacobians(self.model, self.data, np.asarray(q, dtype=np.float64))
        pin.updateFramePlacements(self.model, self.data)
        return pin.getFrameJacobian(self.model, self.data, self._tcp, pin.ReferenceFrame.LOCAL)

    def nearest_equivalent(self, q: np.ndarray, q_ref: np.ndarray) -> np.ndarray:
        """q with each joint shifted by a multiple of 2 pi (within limits) to be closest to q_ref."""
        q_ref = np.asarray(q_ref, dtype=np.float64)
        shifted = q + 2 * np.pi * np.round((q_ref - q) / (2 * np.pi))
        inside = (shifted >= self.lower) & (shifted <= self.upper)
        return np.where(inside, shifted, q)

    def ik_all(self, T_base_target: np.ndarray, q_ref: np.ndarray, tol: float = 1e-6) -> list[np.ndarray]:
        """Every closed-form IK branch (up to 8: shoulder, elbow and wrist each two ways) reaching
        T_base_target, each joint shifted by 2 pi to be nearest q_ref; FK-checked to `tol` m / rad."""
        T_base_target = np.asarray(T_base_target, float).copy()
        R = T_base_target[:3, :3]
        if np.abs(R.T @ R - np.eye(3)).max() > 1e-12:  # the library filters every branch of a slightly
            U, _, Vt = np.linalg.svd(R)                 # non-orthonormal rotation (a float32 pose): use
            T_base_target[:3, :3] = U @ Vt              # the nearest rotation; a rotation stays as it is
        T_base_tool0 = np.ascontiguousarray(T_base_target @ np.linalg.inv(self.T_tool0_tcp))
        found = []
        for q in ur_analytic_ik.ur5.inverse_kinematics(T_base_tool0):
            q = np.asarray(q, float)
            if not np.isfinite(q).all():
                continue
            q = self.nearest_equivalent(q, q_ref)
            if (q < self.lower).any() or (q > self.upper).any():
                continue
            error = np.linalg.inv(self.fk(q)) @ T_base_target
            if np.abs(error[:3, 3]).max() < tol and np.abs(error[:3, :3] - np.eye(3)).max() < tol:
                found.append(q)
        return found

    def ik_nearest(self, T_base_target: np.ndarray, q_ref: np.ndarray) -> np.ndarray | None:
        """The closed-form IK branch nearest q_ref (max joint difference), or None out of reach."""
        found = self.ik_all(T_base_target, q_ref)
        return min(found, key=lambda q: float(np.abs(q - q_ref).max())) if found else None

    def ik(self, T_base_target: np.ndarray, q_seed: np.ndarray, tol_pos: float = 1e-5,
           tol_rot: float = 1e-4, max_iter: int = 300, damping: float = 1e-3) -> np.ndarray | None:
        """Joint positions reaching T_base_target from q_seed by damped least squares, or None.

        Iterates dq = J^T (J J^T + damping^2 I)^-1 log6(T(q)^-1 T_target), clamped to the limits.
        """
        target = self._base_inv.inverse() * pin.SE3(np.asarray(T_base_target, dtype=np.float64))
        q = np.clip(np.asarray(q_seed, dtype=np.float64).copy(), self.lower, self.upper)
        eye = np.eye(6)
        for _ in range(max_iter):
            self._update(q)
            err = pin.log6(self.data.oMf[self._tcp].actInv(target)).vector  # (6,) in the TCP frame
            if np.linalg.norm(err[:3]) < tol_pos and np.linalg.norm(err[3:]) < tol_rot:
                return self.nearest_equivalent(q, q_seed)
            J = pin.computeFrameJacobian(self.model, self.data, q, self._tcp, pin.ReferenceFrame.LOCAL)
            dq = J.T @ np.linalg.solve(J @ J.T + damping ** 2 * eye, err)
            step = np.linalg.norm(dq)
            if step > 0.5:
                dq *= 0.5 / step
            q = np.clip(q + dq, self.lower, self.upper)
        return None
