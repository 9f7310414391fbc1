"""Hardware-in-the-loop: `nift serve` in another process on loopback, and the faults a network and
a controller produce. Each server is started as a user would and stopped at the end; no process
or port is left behind (checked)."""
import socket
import threading
import time

import numpy as np
import pytest
import zmq

from app.bench.served import served_cell
from hardware.interfaces import ProtectiveStopError
from hardware.net import wire
from hardware.net.client import DeviceRefusedError, NetArm, NetClient, NetDeviceConfig, NetGripper
from hardware.net.discovery import DeviceNotFoundError, find
from hardware.net.keys import ClientKeys, as_client, client_keys, make_keys
from hardware.robot_description import HOME_Q

pytestmark = pytest.mark.hil
FAR = np.array(HOME_Q) + [0.8, 0.3, -0.3, 0.3, 0.0, 0.8]  # free space, ~2 s of motion


def _port_open(address: str) -> bool:
    host, port = address.removeprefix("tcp://").rsplit(":", 1)
    with socket.socket() as s:
        s.settimeout(0.5)
        return s.connect_ex((host, int(port))) == 0


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """A realtime served cell (motions take their real time, as on a controller)."""
    keys = tmp_path_factory.mktemp("hil") / "keys"
    with served_cell(keys, "--realtime", "--name", "nift-test", "--watchdog", "0.3") as (address, proc):
        yield address, keys, proc
    assert proc.returncode is not None and not _port_open(address)  # nothing left behind


def _arm(server, **kw) -> NetArm:
    address, keys, _ = server
    arm = NetArm(NetDeviceConfig(address=address, keys=keys, **kw))
    arm.connect()
    return arm


@pytest.fixture
def arm(server):
    a = _arm(server)
    a.unlockProtectiveStop()
    if np.abs(a.getActualQ() - HOME_Q).max() > 1e-3:
        assert a.moveJ(HOME_Q, speed=3.0, acceleration=8.0)
    yield a
    a.disconnect()


def test_state_reads_round_trip(arm):
    q = arm.getActualQ()
    assert q.shape == (6,) and np.abs(q - HOME_Q).max() < 1e-3
    assert np.allclose(arm.getForwardKinematics(q), arm.getActualTCPPose(), atol=1e-6)
    assert arm.joint_limits.contains(q) and not arm.isProtectiveStopped()


def test_a_motion_over_the_network_arrives(arm):
    target = np.array(HOME_Q) + [0.2, 0.0, 0.0, 0.0, 0.0, 0.2]
    assert arm.moveJ(target, speed=3.0, acceleration=8.0)
    assert np.abs(arm.getActualQ() - target).max() < 0.01


def test_a_client_key_the_server_does_not_hold_is_refused_and_the_arm_does_not_move(server, arm, tmp_path):
    address, keys, _ = server
    make_keys(tmp_path / "stranger")
    stranger = client_keys(tmp_path / "stranger")
    intruder = NetClient(address, ClientKeys(stranger.public, stranger.secret, client_keys(keys).server), "arm")
    with pytest.raises(DeviceRefusedError, match="refused this client's key"):
        intruder.call("moveJ", FAR)
    intruder.close()
    time.sleep(0.3)
    assert np.abs(arm.getActualQ() - HOME_Q).max() < 1e-3
    assert any("refused a connection: client key" in line for line in server[2].log)  # and it was logged


def test_garbage_and_oversized_messages_get_an_error_reply_and_the_server_keeps_serving(server, arm):
    address, keys, _ = server
    s = zmq.Context.instance().socket(zmq.REQ)
    s.setsockopt(zmq.RCVTIMEO, 5000)
    s.setsockopt(zmq.LINGER, 0)
    as_client(s, client_keys(keys))  # an allowed client sending garbage
    s.connect(address)
    for payload in (b"\x93garbage", b"\x00" * (wire.MAX_MESSAGE + 1)):
        s.send(payload)
        reply = wire.unpack(s.recv())
        assert not reply["ok"] and reply["error"] == "WireError"
    s.close()
    assert arm.getActualQ().shape == (6,)


def test_nan_joints_and_trajectories_outside_the_limits_are_refused(arm):
    with pytest.raises(ValueError, match="finite"):
        arm.moveJ(np.full(6, np.nan))
    q0 = arm.getActualQ()
    beyond = np.linspace(q0, q0 + [0, 0, 0, 0, 0, 10.0], 20)
    with pytest.raises(ValueError, match="joint limits"):
        arm.executeTrajectory(np.linspace(0, 2, 20), beyond)
    assert np.abs(arm.getActualQ() - q0).max() < 1e-3


def test_a_second_client_may_read_but_not_command(server, arm):
    assert arm.moveJ(np.array(HOME_Q) + [0.1, 0, 0, 0, 0, 0], speed=3.0, acceleration=8.0)  # arm now commands
    other = _arm(server)
    try:
        assert other.getActualQ().shape == (6,)
        with pytest.raises(DeviceRefusedError, match="commanded by another client"):
            other.moveJ(HOME_Q)
        arm.disconnect()  # releases the arm
        assert other.moveJ(HOME_Q, speed=3.0, acceleration=8.0)
    finally:
        other.disconnect()
        arm.connect()


def test_stopJ_is_answered_while_a_motion_runs(arm, server):
    outcome = {}
    mover = threading.Thread(target=lambda: outcome.update(arrived=arm.moveJ(FAR, speed=1.0, acceleration=2.0)))
    mover.start()
    time.sleep(0.5)
    start = time.monotonic()
    arm.stopJ()
    answered = time.monotonic() - start
    mover.join(10)
    # FAR is 1.3 s away at this speed and acceleration: the stop is answered well inside the 0.8 s
    # still to go (not queued behind the motion), and the arm stands short of FAR (below).
    assert answered < 0.5 and outcome["arrived"] is False
    assert np.abs(arm.getActualQ() - FAR).max() > 0.1 and np.abs(arm.getActualQd()).max() < 0.05
    assert "stop" in arm.getLastError()


def test_the_watchdog_stops_the_arm_when_its_client_falls_silent(server, arm):
    address, keys, _ = server
    silent = NetClient(address, client_keys(keys), "arm")
    arm.disconnect()  # the silent client takes the arm
    silent.call("moveJ", FAR, 1.0, 2.0)  # submitted; then the client says nothing more
    time.sleep(1.5)
    watcher = _arm(server)
    try:
        q = watcher.getActualQ()
        assert np.abs(q - FAR).max() > 0.1  # stopped short of the target
        assert np.abs(watcher.getActualQd()).max() < 0.05  # and at rest
    finally:
        silent.call("release")
        silent.close()
        watcher.disconnect()
        arm.connect()


def test_the_watchdog_stops_the_arm_within_0_6_s_while_another_client_floods_the_server(server, arm):
    """The commander falls silent mid-motion (watchdog 0.3 s) while a second client sends state reads
    as fast as it can: the arm is at rest within 0.6 s of the commander's last message, read off the
    flood's own replies."""
    address, keys, _ = server
    silent = NetClient(address, client_keys(keys), "arm")
    flooder = NetClient(address, client_keys(keys), "arm")
    arm.disconnect()
    seen: list[tuple[float, float]] = []  # (time, fastest joint speed)
    stop = threading.Event()

    def flood() -> None:
        while not stop.is_set():
            seen.append((time.monotonic(), float(np.abs(flooder.call("getActualQd")).max())))

    try:
        silent.call("moveJ", FAR, 1.0, 2.0)
        last = time.monotonic()  # the commander's last message
        reader = threading.Thread(target=flood, daemon=True)
        reader.start()
        time.sleep(1.5)
        stop.set()
        reader.join(5)
        assert len(seen) > 200  # a flood indeed (one read every few ms)
        moving = [t for t, speed in seen if speed > 0.05]
        assert moving and moving[-1] - last < 0.6, moving[-1] - last if moving else None
    finally:
        silent.call("release")
        silent.close()
        flooder.close()
        arm.connect()


def test_a_protective_stop_reaches_the_client_as_the_same_error(arm):
    into_table = np.array(HOME_Q) + [0.0, 1.3, 0.0, 0.0, 0.0, 0.0]
    assert arm.moveJ(into_table, speed=1.0, acceleration=4.0) is False
    assert arm.isProtectiveStopped() and "protective stop" in arm.getLastError()
    with pytest.raises(ProtectiveStopError):
        arm.moveJ(HOME_Q)
    arm.unlockProtectiveStop()
    assert arm.moveJ(HOME_Q, speed=1.0, acceleration=4.0)


def test_contact_detection_over_the_network_stops_at_the_table_without_a_protective_stop(arm):
    """The same motion into the table as above, under contact detection: a contact, not a stop;
    a threshold that is no force is refused by name."""
    into_table = np.array(HOME_Q) + [0.0, 1.3, 0.0, 0.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="contact detection force"):
        arm.startContactDetection(-5.0)
    assert arm.startContactDetection(30.0)
    assert arm.moveJ(into_table, speed=1.0, acceleration=4.0) is False
    assert arm.readContactDetection() and not arm.isProtectiveStopped()
    assert "contact detected" in arm.getLastError()
    assert np.linalg.norm(arm.getActualTCPForce()[:3]) > 0.0  # the fingers still rest on the table
    assert arm.stopContactDetection()
    assert arm.moveJ(HOME_Q, speed=1.0, acceleration=4.0)


def test_the_gripper_is_served_as_well(server):
    address, keys, _ = server
    g = NetGripper(NetDeviceConfig(address=address, keys=keys))
    with g:
        g.open()
        assert abs(g.width - g.stroke) < 0.005 and not g.object_detected and 0.0 <= g.force < 1.0
        with pytest.raises(ValueError, match="force"):
            g.close(force=-1.0)


def test_discovery_finds_devices_by_kind_and_names_what_it_found(server):
    address, _, _ = server
    assert find("arm", "nift-test-arm", timeout=5.0).address == address
    with pytest.raises(DeviceNotFoundError, match="found .*nift-test-arm"):
        find("arm", "no-such-arm", timeout=1.5)


def test_one_device_can_be_served_alone(tmp_path):
    with served_cell(tmp_path / "keys", "--devices", "gripper", "--no-advertise") as (address, proc):
        device = NetDeviceConfig(address=address, keys=tmp_path / "keys")
        with NetGripper(device) as g:
            assert g.stroke > 0.05
        with pytest.raises(DeviceRefusedError, match="serving: nift-sim-gripper"):
            NetArm(device).connect()
    assert proc.returncode is not None and not _port_open(address)


@pytest.mark.slow
def test_the_whole_job_over_the_network_matches_the_in_process_cell(tmp_path):
    """`nift run --devices net` against `nift serve` in another process: the same poses and outcome
    as the in-process cell on the same seed."""
    from app.jobs.job import JobConfig
    from app.jobs.remote import NetCell, NetCellConfig, run_remote_series
    from app.layout import CellLayout
    from app.motion.scene import PlanningScene
    from app.simcell.cell import CellConfig, SimCell
    from app.simcell.sim_job import JobSpec, run_sim_job
    from app.tasks.task import task
    with SimCell(CellConfig()) as cell:  # the camera's true pose (calibration is tested on its own)
        T_base_cam = np.array(cell.camera.config.T_base_cam)
    with served_cell(tmp_path / "keys", "--no-advertise") as (address, proc):
        device = NetDeviceConfig(address=address, keys=tmp_path / "keys")
        with NetCell(NetCellConfig(device, device, device, device)) as cell:
            [net] = run_remote_series(cell, CellLayout(), task("bowl"), [0], "upright", T_base_cam, JobConfig())
    assert proc.returncode is not None and not _port_open(address)
    with SimCell(CellConfig()) as cell:
        scene = PlanningScene(CellConfig())
        local = run_sim_job(cell, scene, T_base_cam, JobSpec(task("bowl"), 0, "upright"))
        scene.close()
    assert net.success and local.success, (net.reason, local.reason)
    for stage in ("grasp", "place"):  # on a mismatch, say which pair and attempts each job took
        assert np.allclose(net.poses[stage], local.poses[stage], atol=1e-4), (
            stage, net.attempts, local.attempts, net.candidates[:3], local.candidates[:3], net.look, local.look)
    assert net.info["instance"] == local.info["instance"]


def test_a_terminated_server_stops_its_moving_arm_and_exits_within_a_second(tmp_path):
    """SIGTERM while the arm runs a slow realtime moveJ: the server stops the arm (logged), closes, and
    the process has ended within 1 s; its client's motion ends without arriving."""
    import signal
    import threading

    with served_cell(tmp_path / "keys", "--realtime", "--no-advertise") as (address, proc):
        arm = NetArm(NetDeviceConfig(address=address, keys=tmp_path / "keys"))
        arm.connect()
        outcome = {}

        def move() -> None:
            try:
                outcome["arrived"] = arm.moveJ(np.asarray(HOME_Q) + [1.0, 0, 0, 0, 0, 0], 0.3, 1.0)
            except Exception as exc:  # noqa: BLE001 - the server goes away: any failure is an outcome
                outcome["error"] = type(exc).__name__

        mover = threading.Thread(target=move, daemon=True)
        mover.start()
        time.sleep(1.0)
        start = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        proc.wait(10)
        took = time.monotonic() - start
        mover.join(5)
        arm.disconnect()
    assert took < 1.0 and proc.returncode == 0, took
    assert outcome.get("arrived") is not True
    assert any("server shutting down" in line for line in proc.log)


def test_a_killed_server_leaves_no_process_behind(tmp_path):
    """kill -9 of `nift serve`: within 2 s neither it nor any process it started is alive."""
    import psutil

    with served_cell(tmp_path / "keys", "--no-advertise") as (address, proc):
        family = [psutil.Process(proc.pid), *psutil.Process(proc.pid).children(recursive=True)]
        proc.kill()
        _, alive = psutil.wait_procs(family, timeout=2.0)
    assert alive == [] and not _port_open(address)


def test_another_clients_captures_do_not_slow_the_commanders_motion(server, arm):
    """A realtime moveJ timed alone, then again while a second client asks for captures and reads the
    arm's state as fast as it can: the captures are refused Busy (the served devices share one motion
    thread), the reads answered, and the motion takes at most 10 % longer."""
    address, keys, _ = server
    target = np.array(HOME_Q) + [0.5, 0, 0, 0, 0, 0]

    def timed_move(q) -> float:
        start = time.monotonic()
        assert arm.moveJ(q, speed=1.0, acceleration=4.0)
        return time.monotonic() - start

    alone = timed_move(target)
    timed_move(np.array(HOME_Q))
    camera = NetClient(address, client_keys(keys), "camera")
    refused, stop = [], threading.Event()

    watcher = NetClient(address, client_keys(keys), "arm")
    reads = []

    def flood() -> None:
        while not stop.is_set():
            try:
                camera.call("capture")
            except DeviceRefusedError as exc:
                refused.append(str(exc))
            reads.append(watcher.call("getActualQ"))

    reader = threading.Thread(target=flood, daemon=True)
    reader.start()
    try:
        time.sleep(0.05)
        crowded = timed_move(target)
    finally:
        stop.set()
        reader.join(5)
        camera.call_quietly("release")
        camera.close()
        watcher.close()
    assert refused and "another client commands" in refused[0] and len(reads) > 10
    assert crowded <= 1.10 * alone, (alone, crowded)


def _poll_until_gone(client: NetClient) -> None:
    """Poll the client's first job until the server answers no more (as `NetClient.run` does)."""
    try:
        while not client.call("result", 1, 0.02, deadline=2.0)["done"]:
            pass
    except Exception:  # noqa: BLE001 - the server went away: the end of the polling
        pass


def test_a_terminated_server_does_not_wait_for_a_rig_job(tmp_path):
    """SIGTERM while the rig calibrates the camera (20 views, realtime: many seconds): the arm is stopped
    and the process has ended within 1 s."""
    import signal

    with served_cell(tmp_path / "keys", "--realtime", "--no-advertise") as (address, proc):
        rig = NetClient(address, client_keys(tmp_path / "keys"), "sim")
        caller = threading.Thread(target=lambda: rig.call_quietly("calibrate") or _poll_until_gone(rig), daemon=True)
        caller.start()  # submitted, then polled (the polls feed the watchdog)
        time.sleep(1.5)
        start = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        proc.wait(10)
        took = time.monotonic() - start
        rig.close()
    assert took < 1.0 and proc.returncode == 0, took
    assert any("server shutting down" in line for line in proc.log), proc.log[-5:]


def test_replies_a_client_never_reads_are_bounded(tmp_path):
    """A client asks for the last 1.5 MB frame 300 times and reads no reply (450 MB unbounded): the
    server keeps at most QUEUED_REPLIES of them for it, its memory grows by far less, and it still
    answers another client."""
    import psutil

    from hardware.net.server import QUEUED_REPLIES

    keys = tmp_path / "keys"
    with served_cell(keys, "--no-advertise") as (address, proc):
        camera = NetClient(address, client_keys(keys), "camera")
        camera.run("capture")
        server = psutil.Process(proc.pid)
        before = server.memory_info().rss
        greedy = zmq.Context.instance().socket(zmq.DEALER)
        greedy.setsockopt(zmq.LINGER, 0)
        greedy.setsockopt(zmq.RCVHWM, 1)  # it reads nothing: what the server sends waits on the server's side
        as_client(greedy, client_keys(keys))
        greedy.connect(address)
        for _ in range(300):
            greedy.send_multipart([b"", wire.request("greedy", "camera", "last_frame")])
        time.sleep(3.0)
        grown = (server.memory_info().rss - before) / 2**20
        assert camera.call("intrinsics")["width"] == 512  # still answering
        greedy.close()
        camera.close()
    assert grown < (QUEUED_REPLIES + 16) * 1.6, grown  # at most the queued replies and the socket buffers
