"""Where fan-out runs: a local Ray started for the command, or a cluster the user started.

Locally Ray gets `workers` CPUs (one task per core by default), its dashboard off, and its
processes tied to the command (`guard`); it starts and stops in a thread of its own (`Startup`), so
that the command can work while it starts. With an address, the command joins that cluster: it
checks first that something answers there, so a wrong address fails in one line instead of
Ray's minute of retries.
"""
from __future__ import annotations

import logging
import os
import socket
import threading
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import Callable, Iterator

THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")  # one BLAS/OpenMP thread per task
CONNECT_TIMEOUT = 3.0  # s to wait for a cluster's head to accept a connection


class ClusterError(ValueError):
    """No cluster answers at the address, or it runs another Ray or Python than this command."""


@dataclass(frozen=True)
class ClusterConfig:
    """How many tasks run at once, and where (None: a local Ray for this command)."""

    workers: int = 2
    address: str | None = None
    startup: "Startup | None" = field(default=None, compare=False, repr=False)  # a local Ray already starting

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


def _init_arguments(config: ClusterConfig) -> dict:
    """ray.init's arguments: dashboard and log forwarding off; remote workers get one BLAS thread each."""
    _quiet_ray()
    for name in THREAD_VARIABLES:  # local workers inherit them; remote ones get them from the runtime env
        os.environ.setdefault(name, "1")
    common = dict(include_dashboard=False, log_to_driver=False, configure_logging=True, logging_level=logging.ERROR,
                  runtime_env={"env_vars": {n: "1" for n in THREAD_VARIABLES}} if not config.local else None)
    if config.local:
        common.update(address="local", num_cpus=config.workers)  # never a cluster found on this machine
    return common


class Startup:
    """A local Ray that lives in a thread of its own: ray.init waits seconds on its servers, and the
    command works meanwhile. Callbacks given to `when_up` run once it is up; `join` re-raises a failed
    start. The thread shuts Ray down too (`stop`): shut down from another thread, Ray 2.60 waits 5 s more."""

    def __init__(self, config: ClusterConfig) -> None:
        self._done = threading.Event()  # set once ray.init has returned or failed, and the callbacks have run
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._up = False  # ray.init has returned or failed (callbacks given from now on run in the caller)
        self._callbacks: list[Callable[[], None]] = []
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._life, args=(config,), name="ray", daemon=True)
        self._thread.start()

    def _life(self, config: ClusterConfig) -> None:
        import ray

        try:
            ray.init(**_init_arguments(config))
        except BaseException as exc:  # noqa: BLE001 - handed to the command's thread by join()
            self._error = exc
        with self._lock:
            self._up, callbacks, self._callbacks = True, self._callbacks, []
        for callback in callbacks:
            self._call(callback)
        self._done.set()
        self._stop.wait()
        ray.shutdown()

    def _call(self, callback: Callable[[], None]) -> None:
        if self._error is None:
            try:
                callback()
            except BaseException as exc:  # noqa: BLE001 - handed to the command's thread by join()
                self._error = exc

    def when_up(self, callback: Callable[[], None]) -> None:
        """`callback()` once Ray is up: in Ray's thread then, or here if it is up already."""
        with self._lock:
            if not self._up:
                self._callbacks.append(callback)
                return
        self._done.wait()
        self._call(callback)

    def join(self) -> None:
        """Wait for the start and its callbacks; the exception, if one failed, raised here."""
        self._done.wait()
        if self._error is not None:
            raise self._error

    def stop(self) -> None:
        """Ray shut down (after its start, if that is still under way)."""
        self._stop.set()
        self._thread.join()


@contextmanager
def _local_ray(config: ClusterConfig) -> Iterator[Startup]:
    """A local Ray starting for the block, its processes guarded, shut down after it."""
    from app.fanout.guard import guarded

    with guarded():
        startup = Startup(config)
        try:
            yield startup
        finally:
            startup.stop()


@contextmanager
def warmed(config: ClusterConfig) -> Iterator[ClusterConfig]:
    """The config with a local Ray starting in the background for the block (`startup`), shut down after
    it; unchanged for one worker (no Ray), a cluster at an address (joined when the work starts), or a
    config whose Ray is already starting."""
    if not config.local or config.workers <= 1 or config.startup is not None:
        yield config
        return
    with _local_ray(config) as startup:
        yield replace(config, startup=startup)


@contextmanager
def started(config: ClusterConfig) -> Iterator[None]:
    """Ray up for the block (started, or joined at `config.address`), shut down after it."""
    import ray

    if config.local:
        with _local_ray(config) as startup:
            startup.join()
            yield
        return
    check_reachable(config.address)
    try:
        ray.init(address=config.address, **_init_arguments(config))
    except (ConnectionError, RuntimeError) as exc:  # RuntimeError: Ray's version check
        ray.shutdown()  # a half-made connection
        raise ClusterError(f"--address {config.address}: {' '.join(str(exc).split())}") from None
    try:
        yield
    finally:
        ray.shutdown()
