"""Motion planning for the cell: a collision model, multi-seed IK, Ruckig trajectories, Cartesian lines."""
