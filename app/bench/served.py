"""`nift serve` started as a user would, in a subprocess on loopback, for the hardware-in-the-loop
benchmark and tests: it waits for the server's "serving ..." line and stops the process (SIGTERM,
then SIGKILL) on the way out, so no process or port is left behind."""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

SERVING = re.compile(r"serving (.+) on (tcp://[\d.]+:\d+)")


@contextmanager
def served_cell(keys: Path, *extra: str, start_timeout: float = 120.0) -> Iterator[tuple[str, subprocess.Popen]]:
    """(address, process) of a `nift serve --keys KEYS EXTRA...` running until the block ends (the key
    folder made on its start);
    `process.log` holds the lines of its log (stderr) so far."""
    command = [sys.executable, "-c", "from app.cli import main; raise SystemExit(main())", "serve",
               "--keys", str(keys), *extra]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    errors: list[str] = []
    threading.Thread(target=lambda: errors.extend(proc.stderr), daemon=True).start()  # the server's log
    proc.log = errors  # its lines so far, for tests
    try:
        address = _wait_for_address(proc, start_timeout, errors)
        yield address, proc
    finally:
        stop(proc)


def _wait_for_address(proc: subprocess.Popen, timeout: float, errors: list[str]) -> str:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        line = proc.stdout.readline()
        if not line:
            if proc.poll() is not None:
                raise RuntimeError(f"nift serve exited ({proc.returncode}): {''.join(errors[-3:]).strip()}")
            time.sleep(0.05)
            continue
        if m := SERVING.search(line):
            threading.Thread(target=lambda: [None for _ in proc.stdout], daemon=True).start()
            return m.group(2)
    raise TimeoutError(f"nift serve did not start within {timeout:g} s")


def stop(proc: subprocess.Popen, timeout: float = 10.0) -> int:
    """Terminate the server and wait for it; kill it if it does not end."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.returncode
