"""Device interfaces (Arm, Gripper, DepthCamera) and their implementations; see the cell issue."""
