"""Device interfaces (Arm, Gripper, DepthCamera) and their implementations; see the cell issue."""


def _import_pybullet_quietly() -> None:
    """Import pybullet with fds 1 and 2 pointed at /dev/null: its C module prints a build banner,
    which would spoil one-line errors and piped output. Later imports find it loaded. Without
    pybullet installed (a GPU box that only trains fields) nothing happens: the simulated devices
    then fail on their own import."""
    import ctypes
    import importlib.util
    import os
    import sys

    if "pybullet" in sys.modules or importlib.util.find_spec("pybullet") is None:
        return
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    try:
        import pybullet  # noqa: F401

        ctypes.CDLL(None).fflush(None)  # whatever C buffered goes to /dev/null too
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, devnull):
            os.close(fd)


_import_pybullet_quietly()
