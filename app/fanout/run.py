"""One task per item on Ray, each outcome yielded as it finishes.

A task is `work(state, item)`, where `state = setup(payload)` is made once per worker process and
kept for the run's later items on that worker (a PyBullet world, a bench): the world is built
inside the worker, and the payload (settings, shipped files) travels once per node through the
object store. After `recycle_after` items a worker process exits and a fresh one takes its place,
which bounds its memory. A worker that dies mid-task (kill -9, a node lost) has its task run again
(`retries`); a task that raises is an `Outcome` with the error, and the others go on.

A local Ray takes seconds to start (its servers, then each worker's imports). Where a worker's state
costs nothing to make (`helps=True`: make-data's shards), the command's own process works on the items
in order while it starts, and Ray's workers take the rest once it is up; where the state is a world
to build (bench, bench-jobs), a third one on two cores would cost more than it saves. A cluster at an
address is joined before any work. `--workers 1` runs every item in this process, in order, without
Ray: the path for a debugger.
"""
from __future__ import annotations

import sys
import threading
import uuid
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Sequence

from app.fanout.cluster import ClusterConfig, Startup, started, warmed

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


def _run_here(work: Callable[[Any, Any], Any], state: Any, index: int, item: Any) -> Outcome:
    """One item in this process; its exception is the outcome's error, as on Ray."""
    try:
        return Outcome(index, work(state, item))
    except Exception as exc:  # noqa: BLE001 - a failed item is a row with its error, as on Ray
        return Outcome(index, error=one_line(exc))


def in_process(work: Callable[[Any, Any], Any], items: Sequence[Any], setup: Callable[[Any], Any],
               payload: Any) -> Iterator[Outcome]:
    """The items in this process, in order (`--workers 1`); the state is closed at the end."""
    state = setup(payload)
    try:
        for i, item in enumerate(items):
            yield _run_here(work, state, i, item)
    finally:
        getattr(state, "close", lambda: None)()


def submit(work: Callable[[Any, Any], Any], items: Sequence[tuple[int, Any]], setup: Callable[[Any], Any],
           payload: Any, recycle_after: int = 0, retries: int = 3) -> dict:
    """Each (index, item) as a task on the connected cluster: {its result's reference: index}."""
    import ray

    remote = ray.remote(num_cpus=1, max_calls=recycle_after, max_retries=retries, retry_exceptions=False)(_task)
    payload_ref, key = ray.put(payload), uuid.uuid4().hex
    return {remote.remote(work, setup, payload_ref, key, item): i for i, item in items}


def collect(waiting: dict) -> Iterator[Outcome]:
    """The submitted tasks' outcomes, as they finish."""
    import ray
    from ray.exceptions import RayTaskError

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


def on_ray(work: Callable[[Any, Any], Any], items: Sequence[Any], setup: Callable[[Any], Any], payload: Any,
           recycle_after: int = 0, retries: int = 3) -> Iterator[Outcome]:
    """The items as Ray tasks on the connected cluster, yielded as they finish."""
    yield from collect(submit(work, list(enumerate(items)), setup, payload, recycle_after, retries))


def helped(work: Callable[[Any, Any], Any], items: Sequence[Any], setup: Callable[[Any], Any], payload: Any,
           startup: Startup, recycle_after: int = 0) -> Iterator[Outcome]:
    """The items on a local Ray that is starting; this process works on them in order until it is up,
    and the rest are handed to Ray's workers from Ray's thread (not after the item in hand)."""
    todo, lock, waiting = deque(enumerate(items)), threading.Lock(), {}

    def hand_over() -> None:  # once Ray is up
        with lock:
            rest = list(todo)
            todo.clear()
        if rest:
            waiting.update(submit(work, rest, setup, payload, recycle_after))

    startup.when_up(hand_over)
    state = None
    try:
        while True:
            with lock:
                if not todo:
                    break
                index, item = todo.popleft()
            state = setup(payload) if state is None else state
            yield _run_here(work, state, index, item)
    finally:
        getattr(state, "close", lambda: None)()
    startup.join()  # Ray's start failed: its error here, after the items done so far
    yield from collect(waiting)


def fan_out(work: Callable[[Any, Any], Any], items: Sequence[Any], setup: Callable[[Any], Any], payload: Any,
            cluster: ClusterConfig, recycle_after: int = 0, helps: bool = False) -> Iterator[Outcome]:
    """`work(setup(payload), item)` for every item: in this process for one local worker; on a local Ray
    started for the run (`helps`: with this process working while it starts); or on the cluster at the
    address."""
    if cluster.local and cluster.workers <= 1:
        yield from in_process(work, items, setup, payload)
    elif cluster.local:
        with warmed(cluster) as warm:  # already starting if the command warmed it
            if not helps:
                warm.startup.join()  # up before the work: every item to Ray's workers
            yield from helped(work, items, setup, payload, warm.startup, recycle_after)
    else:
        with started(cluster):
            yield from on_ray(work, items, setup, payload, recycle_after)
