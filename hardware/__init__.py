"""Device interfaces (Arm, Gripper, DepthCamera) and their implementations; see the cell issue."""


def _import_pybullet_quietly() -> None:
    """Import pybullet with fd 1 closed: its C module prints a build banner to stdout, which would
    spoil `--json` output. Every later `import pybullet` finds it already loaded."""
    import os
    import sys

    if "pybullet" in sys.modules:
        return
    sys.stdout.flush()
    saved, devnull = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    try:
        import ctypes

        import pybullet  # noqa: F401

        ctypes.CDLL(None).fflush(None)  # the banner sits in C's stdio buffer until flushed
    finally:
        os.dup2(saved, 1)
        os.close(devnull)
        os.close(saved)


_import_pybullet_quietly()
