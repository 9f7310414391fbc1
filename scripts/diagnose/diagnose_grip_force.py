"""How hard the simulated gripper's pads press a fixed block for each force asked (docs/decisions.md,
"The grip force: found, tried three times, not changed"): the fingers close on a static block between the pads, the
world steps 50 more times, and the finger motors' forces and the pads' contact forces are printed.

Usage (repo root): .venv/bin/python scripts/diagnose/diagnose_grip_force.py [FORCE ...]   (default 10 20 30 40 60 N; ~5 s)
"""
import sys

import numpy as np

from app.simcell.cell import CellConfig, SimCell
from hardware.bullet import p


def main(forces: list[float]) -> None:
    with SimCell(CellConfig()) as cell:
        world, robot, gripper = cell.world, cell.robot, cell.gripper
        tcp = robot.link_pose("gripper_palm") @ np.array([0.0, 0.0, robot.geometry.tcp_z, 1.0])
        for force in forces:
            block = world.add_box((0.02, 0.03, 0.02), tcp[:3], mass=0.0)  # static, between the pads
            gripper.open()
            held = gripper.close(force)
            world.step(50)
            motor = [p.getJointState(robot.body, j, physicsClientId=robot.client)[3] for j in robot.finger_joints]
            pads = [sum(c[9] for c in p.getContactPoints(block, robot.body, -1, link, physicsClientId=robot.client))
                    for link in robot.finger_links]
            print(f"asked {force:5.1f} N  held {held}  width {1000 * gripper.width:5.1f} mm  "
                  f"motors {np.round(motor, 1).tolist()} N  pads {np.round(pads, 1).tolist()} N")
            world.remove(block)


if __name__ == "__main__":
    main([float(f) for f in sys.argv[1:]] or [10.0, 20.0, 30.0, 40.0, 60.0])
