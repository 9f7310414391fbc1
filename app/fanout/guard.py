"""Ray's processes go when the command that started them goes, even by SIGKILL.

Ray ties its servers to the starting process with the kernel's parent-death signal, but the agents
its raylet starts (dashboard and runtime-env agents) outlive a driver killed with SIGKILL. The guard
is a small process of its own session: it notes the driver's Ray descendants every quarter second,
and when the driver's pipe closes (an exit, or a kill) it kills the ones still there. No library
offers this for a process tree that re-parents itself, hence these lines over psutil.

Run as `python -m app.fanout.guard PID`, with the driver's end of a pipe as stdin.
"""
from __future__ import annotations

import os
import select
import subprocess
import sys
from contextlib import contextmanager
from typing import Iterator

import psutil

POLL = 0.25  # s between looks at the driver's process tree


def is_ray(process: psutil.Process) -> bool:
    """Whether a process is one of Ray's: its servers, agents and workers."""
    try:
        name, cmdline = process.name(), " ".join(process.cmdline())
    except (psutil.NoSuchProcess, psutil.AccessDenied):
        return False
    return name in ("raylet", "gcs_server") or cmdline.startswith("ray::") or "/site-packages/ray/" in cmdline


def ray_descendants(driver: int) -> dict[int, float]:
    """The driver's Ray descendants, pid -> start time (so a reused pid is never mistaken for one)."""
    try:
        children = psutil.Process(driver).children(recursive=True)
    except psutil.NoSuchProcess:
        return {}
    found = {}
    for p in children:
        try:
            if p.pid != os.getpid() and is_ray(p):
                found[p.pid] = p.create_time()
        except psutil.NoSuchProcess:
            continue
    return found


def reap(seen: dict[int, float]) -> None:
    """SIGKILL every noted process still running (and the children it has now), then wait for them."""
    doomed = []
    for pid, started in seen.items():
        try:
            p = psutil.Process(pid)
            if p.create_time() == started:
                doomed += [p, *p.children(recursive=True)]
        except psutil.NoSuchProcess:
            continue
    for p in doomed:
        try:
            p.kill()
        except psutil.NoSuchProcess:
            pass
    psutil.wait_procs(doomed, timeout=5)


def watch(driver: int) -> None:
    """Note the driver's Ray processes until stdin closes, then reap them."""
    seen: dict[int, float] = {}
    while True:
        ready, _, _ = select.select([sys.stdin], [], [], POLL)
        seen.update(ray_descendants(driver))
        if ready and not os.read(sys.stdin.fileno(), 4096):
            break
    reap(seen)


@contextmanager
def guarded() -> Iterator[None]:
    """A guard watches this process's Ray descendants for the block and reaps them after it."""
    guard = subprocess.Popen([sys.executable, "-m", "app.fanout.guard", str(os.getpid())], stdin=subprocess.PIPE,
                             start_new_session=True)  # its own session: a Ctrl-C to the command does not reach it
    try:
        yield
    finally:
        guard.stdin.close()
        guard.wait(timeout=30)


if __name__ == "__main__":
    watch(int(sys.argv[1]))
