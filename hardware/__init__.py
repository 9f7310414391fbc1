"""The device layer: interfaces (Arm, Gripper, DepthCamera), the UR5's kinematics and description,
the gripper's geometry, and the SE(3) module at the bottom of the house (`hardware.se3`).

Importing this package loads nothing heavy: `hardware.sim` holds the PyBullet devices, and
`hardware.bullet` is where pybullet is imported (quietly). See docs/design.md.
"""
