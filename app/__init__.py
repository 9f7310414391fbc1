"""NIFT cell: teach-by-demonstration pick-and-place (the application and the method); see docs/design.md."""

__version__ = "0.1.0"
