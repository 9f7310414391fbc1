"""The device server against malformed requests: no message stops it or moves the arm (a fake UR5
served in a thread; the realtime served cell is `tests/test_hil.py`)."""
import threading
from contextlib import contextmanager

import msgpack
import numpy as np
import pytest
import zmq
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hardware.fake.arm import FakeArm
from hardware.net import wire
from hardware.net.keys import as_client, as_server, client_keys, make_keys, server_keys
from hardware.net.request import MAX_DEPTH
from hardware.net.server import BUILTIN, DeviceServer, ServerConfig
from hardware.net.verbs import device_service

@pytest.fixture(scope="module")
def keys(tmp_path_factory):
    """A key folder as `nift serve --make-keys` makes it."""
    folder = tmp_path_factory.mktemp("keys")
    make_keys(folder)
    return folder


@contextmanager
def serving(keys):
    """A fake arm served in a thread, and one REQ socket to it."""
    arm = FakeArm()
    arm.connect()
    server = DeviceServer({"arm": device_service("arm", arm)}, ServerConfig(server_keys(keys)))
    server.start()
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    sock = connect(server, keys)
    try:
        yield server, arm, sock, thread
    finally:
        server.stop()
        thread.join(5)
        server.close()
        sock.close()


def connect(server: DeviceServer, keys) -> zmq.Socket:
    sock = zmq.Context.instance().socket(zmq.REQ)
    sock.setsockopt(zmq.RCVTIMEO, 3000)
    sock.setsockopt(zmq.LINGER, 0)
    as_client(sock, client_keys(keys))
    sock.connect(f"tcp://127.0.0.1:{server.port}")
    return sock


@pytest.fixture(scope="module")
def served(keys):
    with serving(keys) as s:
        yield s


def ask(sock: zmq.Socket, payload: bytes) -> dict:
    sock.send(payload)
    return wire.unpack(sock.recv())


def raw_request(**fields: bytes) -> bytes:
    """A request map whose values are given as raw msgpack bytes (msgpack's packer will not nest 1,000 deep)."""
    return bytes([0x80 | len(fields)]) + b"".join(
        msgpack.packb(k) + v for k, v in fields.items())


def nested(levels: int) -> bytes:
    return b"\x91" * levels + b"\x01"  # [[[...[1]...]]]


def fields(**override) -> dict[str, bytes]:
    base = {"v": wire.PROTOCOL, "client": "fuzz", "device": "arm", "verb": "getActualQ", "args": []}
    return {k: (v if isinstance(v, bytes) else msgpack.packb(v)) for k, v in {**base, **override}.items()}


def still_serving(sock: zmq.Socket, arm: FakeArm) -> None:
    reply = ask(sock, wire.request("fuzz", "arm", "getActualQ"))
    assert reply["ok"] and np.allclose(reply["value"], arm.getActualQ())


@pytest.mark.parametrize("case, payload", [
    ("a version nested 1,000 deep", raw_request(**fields(v=nested(1000)))),
    ("a device named by a list", raw_request(**fields(device=msgpack.packb(["arm"])))),
    ("a device named by a map", raw_request(**fields(device=msgpack.packb({"arm": 1})))),
    ("a verb nested deep", raw_request(**fields(verb=nested(900)))),
    ("args nested beyond the limit", raw_request(**fields(args=nested(MAX_DEPTH + 2)))),
    ("args that are not a list", raw_request(**fields(args=msgpack.packb({"q": 1})))),
    ("an unknown field", raw_request(**fields(extra=msgpack.packb(1)))),
    ("a client name of 10,000 characters", raw_request(**fields(client=msgpack.packb("c" * 10_000)))),
])
def test_a_malformed_request_is_answered_as_a_wire_error_and_the_server_serves_on(served, case, payload):
    server, arm, sock, thread = served
    reply = ask(sock, payload)
    assert not reply["ok"] and reply["error"] == "WireError", (case, reply)
    assert len(reply["message"]) < 300 and "\n" not in reply["message"]
    assert thread.is_alive()
    still_serving(sock, arm)


def test_an_unexpected_failure_inside_the_server_is_answered_and_the_loop_goes_on(served, monkeypatch):
    server, arm, sock, thread = served
    monkeypatch.setattr(server, "_handle", lambda payload, key: {}["no such key"])
    reply = ask(sock, wire.request("fuzz", "arm", "getActualQ"))
    assert not reply["ok"] and reply["error"] == "InternalError" and "KeyError" in reply["message"]
    monkeypatch.undo()
    assert thread.is_alive()
    still_serving(sock, arm)


SCALARS = st.none() | st.booleans() | st.integers(-2**63, 2**64 - 1) | st.floats() | st.text(max_size=8) | st.binary(max_size=8)
VALUES = st.recursive(SCALARS, lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=4), inner, max_size=3),
                      max_leaves=6)
NOT_A_VERB = st.text(max_size=12).filter(lambda v: v not in device_service("arm", FakeArm()).verbs and v not in BUILTIN)
FIELDS = ("v", "client", "device", "verb", "args")


@st.composite
def malformed(draw) -> list[bytes]:
    """Ten malformed requests from one drawn request map (Hypothesis's cost is in drawing, so each draw
    is sent in ten variants): random bytes, a random value, the drawn map, the map with a valid
    version, client and device and a verb the arm does not have (then nothing may move), and that map
    without each of its five fields, and with a wrong version."""
    message = {k: draw(VALUES) for k in FIELDS if draw(st.booleans())}
    message.update(draw(st.dictionaries(st.text(max_size=6), VALUES, max_size=2)))
    if "verb" in message:  # never, by chance, a verb the arm answers
        message["verb"] = draw(NOT_A_VERB | VALUES.filter(lambda v: not isinstance(v, str)))
    near = {**message, "v": wire.PROTOCOL, "client": "fuzz", "device": "arm",
            "verb": draw(NOT_A_VERB | VALUES.filter(lambda v: not isinstance(v, str)))}
    variants = [message, near, *({k: v for k, v in near.items() if k != key} for key in FIELDS),
                {**near, "v": draw(VALUES.filter(lambda v: v != wire.PROTOCOL))}]
    return [draw(st.binary(max_size=64)), msgpack.packb(draw(VALUES)), *map(msgpack.packb, variants)]


@settings(max_examples=1000, deadline=None, suppress_health_check=list(HealthCheck))
@given(payloads=malformed())
def test_ten_thousand_malformed_requests_leave_the_server_answering_and_the_arm_still(served, payloads):
    """1,000 draws of 10 requests each (see `malformed`)."""
    server, arm, sock, thread = served
    for payload in payloads:
        reply = ask(sock, payload)
        assert reply["ok"] is False and isinstance(reply["error"], str)
    assert arm.motions == [] and np.allclose(arm.getActualQ(), arm.config.home_q)


def test_a_job_result_goes_only_to_the_client_whose_job_it_is(keys):
    """Another client polling the commander's job is told there is no such job, and the commander still
    collects its own result afterwards."""
    with serving(keys) as (server, arm, sock, thread):
        other = connect(server, keys)
        target = np.asarray(arm.getActualQ()) + 0.2
        job = ask(sock, wire.request("commander", "arm", "moveJ", target))["value"]["job"]
        stolen = ask(other, wire.request("other", "arm", "result", job, 0.02))
        assert not stolen["ok"] and "no job" in stolen["message"]
        mine = ask(sock, wire.request("commander", "arm", "result", job, 0.02))
        assert mine["ok"] and mine["value"]["done"] and mine["value"]["value"] is True
        assert np.allclose(arm.getActualQ(), target)
        other.close()


def test_release_puts_back_the_settings_a_client_changed(keys):
    """A commander sets a 0.5 m TCP offset, teach mode and contact detection, then releases: the next
    client finds the server's TCP offset, no teach mode and no contact detection."""
    with serving(keys) as (server, arm, sock, thread):
        tcp0 = np.array(arm.getTCPOffset())
        for verb, *args in (("setTcp", np.array([0, 0, 0.5, 0, 0, 0.0])), ("teachMode",), ("startContactDetection",)):
            assert ask(sock, wire.request("first", "arm", verb, *args))["ok"], verb
        assert arm.isTeachMode() and np.isclose(arm.getTCPOffset()[2], 0.5)
        assert ask(sock, wire.request("first", "arm", "release"))["ok"]
        assert not arm.isTeachMode() and np.allclose(arm.getTCPOffset(), tcp0) and not arm._detecting


def test_a_port_already_in_use_is_an_os_error_naming_it(keys):
    with serving(keys) as (server, arm, sock, thread):
        taken = DeviceServer({}, ServerConfig(server_keys(keys), port=server.port))
        with pytest.raises(OSError, match=f"cannot listen on 127.0.0.1 port {server.port}"):
            taken.start()
        taken.close()


def test_a_rig_verb_that_moves_the_arm_needs_the_arms_commander(keys):
    """A test rig's motions move the arm (`Service.moves`): a second client is refused Busy and the arm
    does not move; the client that commands the arm may use the rig."""
    from hardware.net.verbs import Service, Verb

    arm = FakeArm()
    arm.connect()
    home = np.array(arm.getActualQ())
    rig = Service("sim", arm, {"nudge": Verb(lambda a, _: a.moveJ(home + 0.1), "motion")}, moves=("arm",))
    server = DeviceServer({"arm": device_service("arm", arm), "rig": rig}, ServerConfig(server_keys(keys)))
    server.start()
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    commander, other = connect(server, keys), connect(server, keys)
    try:
        assert ask(commander, wire.request("commander", "arm", "setTcp", np.array(arm.getTCPOffset())))["ok"]
        refused = ask(other, wire.request("other", "rig", "nudge"))
        assert not refused["ok"] and refused["error"] == "Busy" and np.allclose(arm.getActualQ(), home)
        job = ask(commander, wire.request("commander", "rig", "nudge"))["value"]["job"]
        assert ask(commander, wire.request("commander", "rig", "result", job, 0.02))["value"]["done"]
        assert np.allclose(arm.getActualQ(), home + 0.1)
    finally:
        server.stop()
        thread.join(5)
        server.close()
        commander.close()
        other.close()


def test_a_client_whose_server_vanishes_mid_motion_gives_up_within_two_seconds_naming_it(keys):
    """A server that accepts a motion and then falls silent (as after kill -9): the blocking verb raises
    DeviceConnectionLost naming the server within LOST_AFTER, and every later call fails at once."""
    import time

    from hardware.interfaces import DeviceConnectionLost
    from hardware.net.client import LOST_AFTER, NetClient

    router = zmq.Context.instance().socket(zmq.ROUTER)
    router.setsockopt(zmq.LINGER, 0)
    as_server(router, server_keys(keys))  # no authenticator: any client key is let in
    port = router.bind_to_random_port("tcp://127.0.0.1")

    def answer_once() -> None:
        *head, _ = router.recv_multipart()
        router.send_multipart([*head, wire.reply_ok({"job": 1})])  # then silence

    threading.Thread(target=answer_once, daemon=True).start()
    client = NetClient(f"tcp://127.0.0.1:{port}", client_keys(keys), "arm")
    try:
        start = time.monotonic()
        with pytest.raises(DeviceConnectionLost, match=f"lost the device server at tcp://127.0.0.1:{port}"):
            client.run("moveJ", np.zeros(6))
        assert LOST_AFTER <= time.monotonic() - start < LOST_AFTER + 1.0
        start = time.monotonic()
        with pytest.raises(DeviceConnectionLost):
            client.call("stopJ")
        assert time.monotonic() - start < 0.1
    finally:
        client.close()
        router.close()
