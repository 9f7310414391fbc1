"""CURVE keys of the device services: the key folder, a client the server does not know, and a
captured session replayed (a fake UR5 served in a thread; `tests/test_net_server.py` has the rest)."""
import socket
import stat
import threading
import time

import numpy as np
import pytest
import zmq

from hardware.fake.arm import FakeArm
from hardware.net.client import DeviceRefusedError, NetClient
from hardware.net.keys import ClientKeys, KeyFileError, add_client, client_keys, make_keys, server_keys
from hardware.net.server import DeviceServer, ServerConfig
from hardware.net.verbs import device_service


def test_the_key_folder_is_private_made_once_and_loads(tmp_path):
    folder = tmp_path / "keys"
    made = make_keys(folder)
    assert {p.name for p in made} == {"server.key", "server.key_secret", "client.key", "client.key_secret", "this-machine.key"}
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700
    assert all(stat.S_IMODE((folder / f"{n}.key_secret").stat().st_mode) == 0o600 for n in ("server", "client"))
    server, client = server_keys(folder), client_keys(folder)
    assert make_keys(folder) == [] and server_keys(folder) == server  # a second start keeps the keys
    assert client.server == server.public and len(client.secret) == 40 and client.public != server.public
    assert (folder / "clients" / "this-machine.key").read_bytes() == (folder / "client.key").read_bytes()
    (folder / "client.key_secret").chmod(0o644)
    with pytest.raises(KeyFileError, match="readable by others"):
        client_keys(folder)


def test_a_file_that_is_not_a_key_is_refused_in_one_line(tmp_path):
    make_keys(tmp_path / "keys")
    bogus = tmp_path / "laptop.key"
    bogus.write_text("curve\n    public-key = \"short\"\n")
    with pytest.raises(KeyFileError, match="laptop.key") as err:
        add_client(tmp_path / "keys", bogus)
    assert "\n" not in str(err.value)
    assert not (tmp_path / "keys" / "clients" / "laptop.key").exists()


@pytest.fixture
def served(tmp_path):
    """A fake arm served with the keys of tmp_path/keys; (server, arm, key folder)."""
    make_keys(tmp_path / "keys")
    arm = FakeArm()
    arm.connect()
    server = DeviceServer({"arm": device_service("arm", arm)}, ServerConfig(server_keys(tmp_path / "keys")))
    server.start()
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield server, arm, tmp_path / "keys"
    server.stop()
    thread.join(5)
    server.close()


def test_a_client_whose_key_the_server_does_not_hold_is_refused_and_nothing_moves(served, tmp_path):
    server, arm, keys = served
    make_keys(tmp_path / "stranger")  # a pair of its own, which the server never allowed
    stranger = client_keys(tmp_path / "stranger")
    intruder = NetClient(f"tcp://127.0.0.1:{server.port}", ClientKeys(stranger.public, stranger.secret, client_keys(keys).server), "arm", timeout=1.0)
    try:
        with pytest.raises(DeviceRefusedError, match="refused this client's key"):
            intruder.call("moveJ", np.asarray(arm.getActualQ()) + 0.3)
    finally:
        intruder.close()
    assert arm.motions == []
    add_client(keys, tmp_path / "stranger" / "client.key")  # allowed: a server started now answers it
    again = DeviceServer({"arm": device_service("arm", arm)}, ServerConfig(server_keys(keys)))
    again.start()
    thread = threading.Thread(target=again.serve_forever, daemon=True)
    thread.start()
    welcome = NetClient(f"tcp://127.0.0.1:{again.port}", ClientKeys(stranger.public, stranger.secret, client_keys(keys).server), "arm", timeout=2.0)
    try:
        assert welcome.call("hello")["kind"] == "arm"
    finally:
        welcome.close()
        again.stop()
        thread.join(5)
        again.close()


def test_a_client_that_trusts_another_server_key_gets_no_answer(served, tmp_path):
    server, arm, keys = served
    make_keys(tmp_path / "other")
    mine = client_keys(keys)
    fooled = NetClient(f"tcp://127.0.0.1:{server.port}", ClientKeys(mine.public, mine.secret, client_keys(tmp_path / "other").server), "arm", timeout=1.0)
    try:
        with pytest.raises((TimeoutError, DeviceRefusedError)):
            fooled.call("moveJ", np.asarray(arm.getActualQ()) + 0.3)
    finally:
        fooled.close()
    assert arm.motions == []


class Tap:
    """A TCP relay that records the bytes a client sends to the server (an eavesdropper on the LAN)."""

    def __init__(self, port: int) -> None:
        self.sent = bytearray()
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port, self.server_port = self.listener.getsockname()[1], port
        threading.Thread(target=self._relay, daemon=True).start()

    def _relay(self) -> None:
        client, _ = self.listener.accept()
        upstream = socket.create_connection(("127.0.0.1", self.server_port))
        threading.Thread(target=self._pump, args=(upstream, client, None), daemon=True).start()
        self._pump(client, upstream, self.sent)

    @staticmethod
    def _pump(source: socket.socket, sink: socket.socket, record: bytearray | None) -> None:
        try:
            while data := source.recv(65536):
                if record is not None:
                    record.extend(data)
                sink.sendall(data)
        except OSError:  # the other side closed first: the relay ends
            pass
        sink.close()


def test_a_captured_session_is_encrypted_and_replayed_it_moves_nothing(served):
    server, arm, keys = served
    tap = Tap(server.port)
    client = NetClient(f"tcp://127.0.0.1:{tap.port}", client_keys(keys), "arm")
    target = np.asarray(arm.getActualQ()) + 0.4
    try:
        assert client.run("moveJ", target) is True
    finally:
        client.close()
    assert len(arm.motions) == 1 and np.allclose(arm.getActualQ(), target)
    captured = bytes(tap.sent)
    assert len(captured) > 200 and b"moveJ" not in captured and target.tobytes() not in captured  # ciphertext
    arm.moveJ(target - 0.4)
    moved = len(arm.motions)
    with socket.create_connection(("127.0.0.1", server.port)) as replay:
        replay.sendall(captured)
        time.sleep(1.0)
    assert len(arm.motions) == moved and np.allclose(arm.getActualQ(), target - 0.4)
    still = NetClient(f"tcp://127.0.0.1:{server.port}", client_keys(keys), "arm")
    try:
        assert np.allclose(still.call("getActualQ"), target - 0.4)  # and the server serves on
    finally:
        still.close()


def test_connections_that_never_authenticate_are_dropped_and_a_client_is_served_meanwhile(served):
    """200 TCP connections held open without a handshake (a stranger exhausting the server's sockets):
    a client with a key is answered while they are open, and after the handshake interval the server
    has closed them (its process holds about as many descriptors as before)."""
    import os

    from hardware.net.server import HANDSHAKE_MS

    server, arm, keys = served
    before = len(os.listdir("/proc/self/fd"))
    idle = [socket.create_connection(("127.0.0.1", server.port)) for _ in range(200)]
    client = NetClient(f"tcp://127.0.0.1:{server.port}", client_keys(keys), "arm", timeout=2.0)
    try:
        start = time.monotonic()
        assert client.call("getActualQ").shape == (6,)
        assert time.monotonic() - start < 0.5
        time.sleep(HANDSHAKE_MS / 1000 + 1.0)
        for s in idle:
            s.settimeout(1.0)
            while s.recv(4096):  # the server's greeting, then the end: closed by the server (a timeout fails)
                pass
    finally:
        for s in idle:
            s.close()
        client.close()
    time.sleep(0.2)
    assert len(os.listdir("/proc/self/fd")) <= before + 10
