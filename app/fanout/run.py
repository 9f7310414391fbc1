"""One task per item on Ray, each outcome yielded as it finishes.

A task is `work(state, item)`, where `state = setup(payload)` is made once per worker process and
kept for the run's later items on that worker (a PyBullet world, a bench): the world is built
inside the worker, and the payload (settings, shipped files) travels once per node through the
object store. After `recycle_after` items a worker process exits and a fresh one takes its place,
which bounds its memory. A worker that dies mid-task (kill -9, a node lost) has its task run again
(`retries`); a task that raises is an `Outcome` with the error, and the others go on.

`--workers 1` runs the items in this process instead, in order: the path for a debugger.
"""
from __future__ import annotations

import sys
import uuid
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Sequence

from app.fanout.cluster import ClusterConfig, started

_STATE: dict[str, Any] = {}  # in a worker process: the state of the run it serves (one run at a time)


@dataclass(frozen=True)
class Outcome:
    """An item's result (`value`), or the one-line error its task raised (`error`: 'Type: message')."""

    index: int
    value: Any = None
    error: str | None = None

    @property
    def failed(self) -> bool:
        return self.error is not None


def one_line(exc: BaseException) -> str:
    """An exception as 'Type: message' on one line."""
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"


def _one_thread() -> None:
    """torch's intra-op threads to one, if the setup imported it (the BLAS ones come from the environment)."""
    if (torch := sys.modules.get("torch")) is not None:
        torch.set_num_threads(1)


def _state(setup: Callable[[Any], Any], payload: Any, key: str) -> Any:
    """This worker's state for run `key`, made on its first item (a former run's is closed first)."""
    if key not in _STATE:
        for old in _STATE.values():
            getattr(old, "close", lambda: None)()
        _STATE.clear()
        _STATE[key] = setup(payload)
        _one_thread()
    return _STATE[key]


def _task(work: Callable[[Any, Any], Any], setup: Callable[[Any], Any], payload: Any, key: str, item: Any) -> Any:
    return work(_state(setup, payload, key), item)


def in_process(work: Callable[[Any, Any], Any], items: Sequence[Any], setup: Callable[[Any], Any],
               payload: Any) -> Iterator[Outcome]:
    """The items in this process, in order (`--workers 1`); the state is closed at the end."""
    state = setup(payload)
    try:
        for i, item in enumerate(items):
            try:
                yield Outcome(i, work(state, item))
            except Exception as exc:  # noqa: BLE001 - a failed item is a row with its error, as on Ray
                yield Outcome(i, error=one_line(exc))
    finally:
        getattr(state, "close", lambda: None)()


def on_ray(work: Callable[[Any, Any], Any], items: Sequence[Any], setup: Callable[[Any], Any], payload: Any,
           recycle_after: int = 0, retries: int = 3) -> Iterator[Outcome]:
    """The items as Ray tasks on the connected cluster, yielded as they finish."""
    import ray
    from ray.exceptions import RayTaskError

    remote = ray.remote(num_cpus=1, max_calls=recycle_after, max_retries=retries, retry_exceptions=False)(_task)
    payload_ref, key = ray.put(payload), uuid.uuid4().hex
    waiting = {remote.remote(work, setup, payload_ref, key, item): i for i, item in enumerate(items)}
    while waiting:
        done, _ = ray.wait(list(waiting), num_returns=1)
        index = waiting.pop(done[0])
        try:
            yield Outcome(index, ray.get(done[0]))
        except RayTaskError as exc:
            yield Outcome(index, error=one_line(exc.cause if exc.cause is not None else exc))
        except ray.exceptions.RayError as exc:  # out of retries: the worker or its node kept dying
            yield Outcome(index, error=one_line(exc))
    # a consumer that stops early (a time budget) leaves tasks queued: the cluster's shutdown drops them


def fan_out(work: Callable[[Any, Any], Any], items: Sequence[Any], setup: Callable[[Any], Any], payload: Any,
            cluster: ClusterConfig, recycle_after: int = 0) -> Iterator[Outcome]:
    """`work(setup(payload), item)` for every item: in this process for one local worker, else on Ray
    (started for the run, or joined at the cluster's address)."""
    if cluster.local and cluster.workers <= 1:
        yield from in_process(work, items, setup, payload)
        return
    with started(cluster):
        yield from on_ray(work, items, setup, payload, recycle_after)
