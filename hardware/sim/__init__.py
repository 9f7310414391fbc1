"""PyBullet implementations of the cell's devices: world, UR5 arm, parallel gripper, Kinect v2."""
