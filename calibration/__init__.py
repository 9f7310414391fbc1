"""Eye-to-hand calibration of the camera: the ChArUco board, the solve, and the calibration file."""
