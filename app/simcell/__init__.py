"""The simulated cell around the devices: world, spawning, judges, the oracle, teach-in, sim jobs, calibration."""
