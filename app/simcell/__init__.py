"""The simulated cell around the devices: the cell, spawning, judges, the oracle, a job in the cell
(`sim_job`), the scripted demonstrator's demos (`scripted_demos`), calibration, the test rig."""
