"""NIFT cell: teach-by-demonstration pick-and-place (the application and the method)."""

__version__ = "0.1.0"

import hardware  # noqa: E402,F401  (loads pybullet without its stdout banner)
