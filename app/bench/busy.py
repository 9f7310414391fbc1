"""Busy processes beside a benchmark: a cell PC that also runs other work (`nift bench-imitation --busy`)."""
from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager

SPIN = "from app.workers import die_with_parent; import sys; die_with_parent(int(sys.argv[1]))\nwhile True: pass"


@contextmanager
def busy_processes(n: int) -> Iterator[list[subprocess.Popen]]:
    """n processes that spin on one core each while the block runs; killed after it, and with this
    process if it is killed first (`app.workers.die_with_parent`)."""
    procs = [subprocess.Popen([sys.executable, "-c", SPIN, str(os.getpid())]) for _ in range(n)]
    try:
        yield procs
    finally:
        for proc in procs:
            proc.kill()
            proc.wait()
