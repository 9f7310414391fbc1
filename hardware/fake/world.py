"""A kinematic world for the fake devices: rigid meshes at poses, no physics. An object the fake
gripper closes on follows the TCP until the gripper lets go; then it stays where it was let go."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh

from hardware.se3 import invert


class NoLink:
    """A fake device has no link to open or close: connect() and disconnect() only flip its state."""

    def _connect(self) -> None:
        pass

    def _disconnect(self) -> None:
        pass


@dataclass
class FakeObject:
    """A rigid mesh (its own frame) at pose T_base_obj; `T_tcp_obj` while a gripper holds it."""

    name: str
    mesh: trimesh.Trimesh
    T_base_obj: np.ndarray
    T_tcp_obj: np.ndarray | None = None

    def in_base(self) -> trimesh.Trimesh:
        """The mesh where the object stands now (base frame)."""
        return self.mesh.copy().apply_transform(self.T_base_obj)


@dataclass
class FakeWorld:
    """The objects and fixed meshes (base frame) the fake camera sees and the fake gripper may hold."""

    objects: list[FakeObject] = field(default_factory=list)
    fixed: list[trimesh.Trimesh] = field(default_factory=list)  # fixtures: seen, never held

    def meshes(self) -> list[trimesh.Trimesh]:
        """Everything in view, base frame."""
        return [*self.fixed, *(o.in_base() for o in self.objects)]

    def between_fingers(self, T_base_tcp: np.ndarray, reach: float = 0.02) -> FakeObject | None:
        """The object whose surface passes within `reach` (m) of the TCP, nearest first; None when none does."""
        near = []
        for o in self.objects:
            d = float(np.abs(trimesh.proximity.signed_distance(o.in_base(), T_base_tcp[None, :3, 3]))[0])
            if d <= reach:
                near.append((d, o))
        return min(near, key=lambda x: x[0])[1] if near else None

    def grip(self, o: FakeObject, T_base_tcp: np.ndarray) -> None:
        o.T_tcp_obj = invert(T_base_tcp) @ o.T_base_obj

    def follow(self, T_base_tcp: np.ndarray) -> None:
        """Held objects move with the TCP (after every motion of the fake arm)."""
        for o in self.objects:
            if o.T_tcp_obj is not None:
                o.T_base_obj = T_base_tcp @ o.T_tcp_obj

    def let_go(self) -> None:
        for o in self.objects:
            o.T_tcp_obj = None
