"""Fan-out on a real local Ray (app.fanout): the same outcomes as in this process, a raising task is
a row and the run goes on, a worker killed mid-task has its task run again, workers are recycled,
shipped files land once per node, and a driver killed with SIGKILL leaves no Ray process behind."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest
from ray import cloudpickle

from app.fanout.cluster import ClusterConfig, ClusterError, check_reachable, started, warmed
from app.fanout.guard import is_ray
from app.fanout.run import fan_out, in_process, on_ray
from app.fanout.shipping import landed, pack

ROOT = Path(__file__).resolve().parents[1]
cloudpickle.register_pickle_by_value(sys.modules[__name__])  # Ray's workers cannot import tests/: ship these functions


def offset(payload: int) -> dict:
    return {"offset": payload}


def square(state: dict, item: int) -> int:
    if item == 3:
        raise ValueError("three is refused")
    return state["offset"] + item * item


def die_once(folder: str, item: int) -> int:
    """Even items kill their worker (SIGKILL, no clean-up) the first time they run."""
    marker = Path(folder) / str(item)
    if item % 2 == 0 and not marker.exists():
        marker.touch()
        os.kill(os.getpid(), signal.SIGKILL)
    return item


def same(payload):
    return payload


def pid_of(state, item: int) -> int:
    return os.getpid()


def test_ray_gives_what_this_process_gives_retries_killed_workers_and_recycles_them(tmp_path, monkeypatch):
    import ray._private.services

    # a cluster `ray start` left on this machine (another test's, a user's): a local run starts its own
    monkeypatch.setattr(ray._private.services, "find_bootstrap_address", lambda temp_dir: "127.0.0.1:9")
    items = list(range(8))
    here = {o.index: o.error or o.value for o in in_process(square, items, offset, 10)}
    with started(ClusterConfig(2)):
        there = {o.index: o.error or o.value for o in on_ray(square, items, offset, 10)}
        survived = sorted(o.value for o in on_ray(die_once, items, same, str(tmp_path)))
        pids = [o.value for o in on_ray(pid_of, range(4), same, None, recycle_after=1)]
    assert there == here and here[3] == "ValueError: three is refused" and here[5] == 35
    assert survived == items and sorted(int(p.name) for p in tmp_path.iterdir()) == [0, 2, 4, 6]  # each died once
    assert len(set(pids)) == 4  # recycled after every task: a fresh process each time


def slow_pid(state, item: int) -> tuple[int, int]:
    if item == 23:
        raise ValueError("the last is refused")
    time.sleep(0.4)
    return item, os.getpid()


def test_the_command_works_while_ray_starts_and_hands_the_rest_to_its_workers():
    items = list(range(24))
    outcomes = list(fan_out(slow_pid, items, same, None, ClusterConfig(2), helps=True))
    assert sorted(o.index for o in outcomes) == items  # each item once
    assert [o.error for o in outcomes if o.failed] == ["ValueError: the last is refused"]
    ran = {o.index: o.value[1] for o in outcomes if not o.failed}
    here = sorted(i for i, pid in ran.items() if pid == os.getpid())
    assert all(o.value[0] == o.index for o in outcomes if not o.failed)
    assert here and here == list(range(len(here)))  # this process took the first items, in order, while Ray started
    assert len(set(ran.values()) - {os.getpid()}) >= 1 and len(here) < len(ran)  # Ray's workers took the rest
    with warmed(ClusterConfig(2)) as ready:
        ready.startup.join()  # Ray up before the work: every item goes to its workers
        pids = {o.value[1] for o in fan_out(slow_pid, [0, 1, 2], same, None, ready, helps=True)}
    unhelped = {o.value[1] for o in fan_out(slow_pid, [0, 1, 2], same, None, ClusterConfig(2))}
    assert os.getpid() not in pids | unhelped
    assert not [p for p in psutil.Process().children(recursive=True) if is_ray(p)]  # Ray shut down after each


def test_a_parcel_lands_once_with_the_same_bytes(tmp_path):
    folder = tmp_path / "demos" / "mug"
    folder.mkdir(parents=True)
    (folder / "demo-00.npz").write_bytes(os.urandom(1000))
    (folder / "nested").mkdir()
    (folder / "nested" / "grasp.nit.npz").write_bytes(b"template")
    parcel = pack(tmp_path / "demos")
    home = landed(parcel)
    assert home.name == "demos" and landed(parcel) == home  # the second call finds it
    assert (home / "mug" / "demo-00.npz").read_bytes() == (folder / "demo-00.npz").read_bytes()
    assert (home / "mug" / "nested" / "grasp.nit.npz").read_bytes() == b"template"
    (folder / "nested" / "grasp.nit.npz").write_bytes(b"another")
    assert pack(tmp_path / "demos").digest != parcel.digest  # new contents, a new landing place
    weights = tmp_path / "nif.pt"
    weights.write_bytes(b"weights")
    assert landed(pack(weights)).read_bytes() == b"weights" and landed(pack(weights)).name == "nif.pt"


def test_an_address_where_nothing_answers_is_one_line():
    with pytest.raises(ClusterError, match="127.0.0.1:9: no Ray cluster answers"):
        check_reachable("127.0.0.1:9")
    with pytest.raises(ClusterError, match="not host:port"):
        check_reachable("head-node")


DRIVER = """
import time
from app.fanout.cluster import ClusterConfig
from app.fanout.run import fan_out

def nap(state, item):
    time.sleep(120)

for outcome in fan_out(nap, [1, 2], lambda payload: None, None, ClusterConfig(2)):
    pass
"""


def ray_descendants(pid: int) -> list[psutil.Process]:
    return [p for p in psutil.Process(pid).children(recursive=True) if is_ray(p)]


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc")
def test_a_driver_killed_with_sigkill_leaves_no_ray_process():
    driver = subprocess.Popen([sys.executable, "-c", DRIVER], cwd=ROOT, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    while not any(p.cmdline()[:1] == ["ray::_task"] for p in ray_descendants(driver.pid)):
        assert time.monotonic() < deadline and driver.poll() is None, "the tasks never started"
        time.sleep(0.2)
    time.sleep(1.0)  # the guard's last look
    ray_processes = ray_descendants(driver.pid)
    assert any(p.name() == "raylet" for p in ray_processes) and len(ray_processes) >= 4
    driver.send_signal(signal.SIGKILL)
    driver.wait()
    gone, alive = psutil.wait_procs(ray_processes, timeout=15)
    for p in alive:
        p.kill()  # the test's own clean-up
    assert alive == [], [p.cmdline() for p in alive]
