"""What a worker process of ours does first: die with the process that started it.

A pool's workers wait on their task queue; when the command that owns them is killed with SIGKILL
(no clean-up runs), they would wait forever. Linux's parent-death signal (`prctl(PR_SET_PDEATHSIG)`,
what Ray's and many supervisors' workers use) kills a worker as soon as its parent is gone. No
library in our dependencies exposes it, hence these few lines over libc.
"""
from __future__ import annotations

import ctypes
import os
import signal

PR_SET_PDEATHSIG = 1  # linux/prctl.h


def die_with_parent(parent: int) -> None:
    """In a worker started by process `parent`: be killed when it dies; exit at once if it already has
    (it may die before this runs). Elsewhere than Linux, only the second half holds."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):  # no libc prctl: not Linux
        pass
    if os.getppid() != parent:
        os._exit(1)
