"""Motion planning for the cell: a collision model, multi-seed IK, a sampling planner (OMPL), Ruckig trajectories,
Cartesian lines and the pick-and-place planner."""
