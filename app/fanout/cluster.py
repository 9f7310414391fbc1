"""Where fan-out runs: a local Ray started for the command, or a cluster the user started.

Locally Ray gets `workers` CPUs (one task per core by default), its dashboard off, and its
processes tied to the command (`guard`). With an address, the command joins that cluster: it
checks first that something answers there, so a wrong address fails in one line instead of
Ray's minute of retries.
"""
from __future__ import annotations

import logging
import os
import socket
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Iterator

THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")  # one BLAS/OpenMP thread per task
CONNECT_TIMEOUT = 3.0  # s to wait for a cluster's head to accept a connection


class ClusterError(ValueError):
    """No cluster answers at the address, or it runs another Ray or Python than this command."""


@dataclass(frozen=True)
class ClusterConfig:
    """How many tasks run at once, and where (None: a local Ray for this command)."""

    workers: int = 2
    address: str | None = None

    @property
    def local(self) -> bool:
        return self.address is None


def cluster_config(workers: int, address: str | None = None) -> ClusterConfig:
    """`--workers` and `--address`, the address defaulting to $RAY_ADDRESS as Ray's own tools do."""
    return ClusterConfig(workers, address or os.environ.get("RAY_ADDRESS") or None)


def check_reachable(address: str) -> None:
    """A one-line ClusterError unless a TCP connection to the head's host:port opens in time."""
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        raise ClusterError(f"--address {address!r} is not host:port (e.g. 10.0.0.5:6379)")
    try:
        socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT).close()
    except OSError as exc:
        raise ClusterError(f"--address {address}: no Ray cluster answers there ({exc.strerror or exc})") from None


def _quiet_ray() -> None:
    """Ray's start-up chatter off the terminal: our commands print figures, and --json must stay clean."""
    os.environ.setdefault("RAY_DEDUP_LOGS", "0")
    logging.getLogger("ray").setLevel(logging.ERROR)
    warnings.filterwarnings("ignore", module="ray")


@contextmanager
def started(config: ClusterConfig) -> Iterator[None]:
    """Ray up for the block (started, or joined at `config.address`), shut down after it."""
    import ray

    from app.fanout.guard import guarded

    _quiet_ray()
    for name in THREAD_VARIABLES:  # local workers inherit them; remote ones get them from the runtime env
        os.environ.setdefault(name, "1")
    common = dict(include_dashboard=False, log_to_driver=False, configure_logging=True, logging_level=logging.ERROR,
                  runtime_env={"env_vars": {n: "1" for n in THREAD_VARIABLES}} if not config.local else None)
    if config.local:
        with guarded():
            ray.init(address="local", num_cpus=config.workers, **common)  # never a cluster found on this machine
            try:
                yield
            finally:
                ray.shutdown()
        return
    check_reachable(config.address)
    try:
        ray.init(address=config.address, **common)
    except (ConnectionError, RuntimeError) as exc:  # RuntimeError: Ray's version check
        ray.shutdown()  # a half-made connection
        raise ClusterError(f"--address {config.address}: {' '.join(str(exc).split())}") from None
    try:
        yield
    finally:
        ray.shutdown()
