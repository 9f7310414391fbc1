"""The simulated gripper squeezes a held object with the force asked (Robotiq-style force setting)."""
import numpy as np
import pytest

from app.sim.cell import CellConfig, SimCell
from hardware.bullet import p


@pytest.mark.parametrize("force", [10.0, 40.0, 60.0])
def test_the_pads_press_a_fixed_block_with_the_force_asked(force):
    """A static block between the pads: each finger's contact force settles at the force asked,
    1 % (before SQUEEZE_SPEED it stopped at about 23 N for anything above that)."""
    with SimCell(CellConfig()) as cell:
        world, robot, gripper = cell.world, cell.robot, cell.gripper
        tcp = robot.link_pose("gripper_palm") @ np.array([0.0, 0.0, robot.geometry.tcp_z, 1.0])
        block = world.add_box((0.02, 0.03, 0.02), tcp[:3], mass=0.0)
        gripper.open()
        assert gripper.close(force)
        world.step(50)
        pressed = [sum(c[9] for c in p.getContactPoints(block, robot.body, -1, link, physicsClientId=robot.client))
                   for link in robot.finger_links]
        assert np.allclose(pressed, force, rtol=0.01), pressed
        assert gripper.object_detected and 0.015 < gripper.width < 0.035  # stopped on the block
