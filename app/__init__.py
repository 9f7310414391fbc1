"""NIFT cell: teach-by-demonstration pick-and-place (the application and the method)."""

__version__ = "0.1.0"
