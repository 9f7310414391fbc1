"""Turning a target cloud into grasp and place poses: the methods, `predict`, and our refinements."""
