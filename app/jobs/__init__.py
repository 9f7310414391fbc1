"""Pick-and-place jobs through the device interfaces: the stages (`job`) and the choice of a
grasp and place pair the cell can execute (`choice`)."""
