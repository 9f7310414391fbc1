"""A worker of ours dies with the command that started it (app.workers): a parent killed with SIGKILL
leaves no worker waiting on its queue."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PARENT = """
import multiprocessing, os, time
from concurrent.futures import ProcessPoolExecutor
from app.workers import die_with_parent
hook = {hook}
with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn"), initializer=hook,
                         initargs=(os.getpid(),) if hook else ()) as pool:
    list(pool.map(abs, range(8)))
    print(*(p.pid for p in multiprocessing.active_children() if "Process" in type(p).__name__), flush=True)
    time.sleep(60)
"""


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/status").read_text().split("State:")[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state != "Z"


def workers_left_after_a_kill(hook: str) -> tuple[list[int], list[int]]:
    """Start a parent whose pool's workers run `hook` first, SIGKILL it: (its workers, those alive 3 s on)."""
    parent = subprocess.Popen([sys.executable, "-c", PARENT.format(hook=hook)], cwd=ROOT, stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True)  # its resource tracker's notes on the kill
    workers = [int(p) for p in parent.stdout.readline().split()]
    parent.send_signal(signal.SIGKILL)
    parent.wait()
    time.sleep(3.0)
    left = [p for p in workers if alive(p)]
    for p in left:
        os.kill(p, signal.SIGKILL)  # the test's own clean-up
    return workers, left


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc")
def test_workers_die_with_a_parent_killed_with_sigkill_where_plain_workers_outlive_it():
    workers, left = workers_left_after_a_kill("die_with_parent")
    assert len(workers) == 2 and left == []
    workers, left = workers_left_after_a_kill("None")  # the check itself: without the hook they stay
    assert len(workers) == 2 and left == workers
