"""The teach page: an operator teaches a task by hand on the live simulated cell, in the browser."""
