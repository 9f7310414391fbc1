"""Clients of the device servers: `NetArm`, `NetGripper`, `NetCamera` implement the same interfaces
as the simulated devices (`hardware.interfaces`), so a job cannot tell them apart.

A blocking verb (moveJ, close, capture ...) is sent, then its job is polled until it ends, each
poll held by the server up to `poll` seconds and answered the moment the job ends; the polls are the watchdog's kicks, so a client that dies or loses the network
stops the arm within the server's watchdog period. stopJ may be sent from another thread while a
motion is being waited for. Errors come back as the exceptions the in-process devices raise:
ProtectiveStopError, DeviceNotConnectedError, ValueError; a refused request raises
`DeviceRefusedError` and a silent server TimeoutError, each in one line. The socket is a CURVE
client (`hardware.net.keys`): it speaks only to the server whose public key it holds, and a server
that refuses its key is named as such (the handshake's failure, read off a socket monitor).
"""
from __future__ import annotations

import threading
import time
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import zmq

from hardware.interfaces import (Arm, CameraIntrinsics, DepthCamera, DeviceConnectionLost, DeviceNotConnectedError, Frame, Gripper,
                                 JointLimits, ProtectiveStopError)
from hardware.net import wire
from hardware.net.keys import DEFAULT_KEY_DIR, ClientKeys, as_client, client_keys


LOST_AFTER = 2.0  # s without a reply to a poll (answered within 20 ms while the server lives): the server is gone


class DeviceRefusedError(PermissionError):
    """The server refused a request or this client's key (another client commands the device, ...)."""


ERRORS = {"ProtectiveStopError": ProtectiveStopError, "DeviceNotConnectedError": DeviceNotConnectedError,
          "ValueError": ValueError, "WireError": ValueError, "TimeoutError": TimeoutError}


@dataclass(frozen=True)
class NetDeviceConfig:
    """Where a networked device is: `address` "tcp://HOST:PORT", or found by `name` (or its kind
    alone) with zeroconf; the CURVE keys in `keys` (`hardware.net.keys`); timeouts in seconds."""

    name: str | None = None  # the advertised name; None: any device of the kind
    address: str | None = None
    keys: Path = DEFAULT_KEY_DIR
    timeout: float = 5.0  # s for one reply
    discovery_timeout: float = 3.0
    poll: float = 0.02  # s each poll of a running motion waits on the server (each poll a watchdog kick)
    motion_timeout: float = 120.0  # s a blocking verb may take
    session: str | None = None  # the client's name to the server; devices of one session share it (None: its own)


class NetClient:
    """One REQ socket to a device server; thread-safe; a reply lost to a timeout is dropped
    (REQ_RELAXED, REQ_CORRELATE) so the next request starts clean."""

    def __init__(self, address: str, keys: ClientKeys, device: str, timeout: float = 5.0, session: str | None = None) -> None:
        self.address, self.device, self.timeout = address, device, timeout
        self.client = session or uuid.uuid4().hex[:12]  # who the server sees: one session commands its devices
        self.note = ""  # the server's note on the last blocking verb (a watchdog stop)
        self.lost = ""  # why the server is taken as gone: every later call fails at once with it
        self._lock = threading.Lock()
        s = zmq.Context.instance().socket(zmq.REQ)
        for option, value in ((zmq.LINGER, 0), (zmq.REQ_RELAXED, 1), (zmq.REQ_CORRELATE, 1),
                              (zmq.RCVTIMEO, int(timeout * 1000)), (zmq.SNDTIMEO, int(timeout * 1000))):
            s.setsockopt(option, value)
        as_client(s, keys)
        self._monitor = s.get_monitor_socket(zmq.EVENT_HANDSHAKE_FAILED_AUTH | zmq.EVENT_HANDSHAKE_FAILED_PROTOCOL)
        s.connect(address)
        self._socket = s

    def call(self, verb: str, *args: Any, deadline: float | None = None) -> Any:
        """The verb's value, or the server's error raised as its exception; `deadline` (s): wait at most
        this long for the reply, and take silence as a lost server (`DeviceConnectionLost`)."""
        with self._lock:
            if self._socket is None:
                raise DeviceNotConnectedError(f"{self.device} is not connected; call connect() first")
            if self.lost:
                raise DeviceConnectionLost(self.lost)
            try:
                if deadline is not None:
                    self._socket.setsockopt(zmq.RCVTIMEO, int(deadline * 1000))
                self._socket.send(wire.request(self.client, self.device, verb, *args))
                reply = wire.unpack(self._socket.recv())
            except zmq.Again:
                if self._handshake_refused():
                    raise DeviceRefusedError(f"{self.device} at {self.address} refused this client's key: add its "
                                             "client.key to the server (nift serve --add-client FILE)") from None
                if deadline is None:
                    raise TimeoutError(f"no reply from {self.device} at {self.address} to {verb} within "
                                       f"{self.timeout:g} s (is `nift serve` running, with this server key?)") from None
                self.lost = (f"lost the device server at {self.address}: {self.device} did not answer a {verb} "
                             f"poll within {deadline:g} s")
                raise DeviceConnectionLost(self.lost) from None
            finally:
                if deadline is not None and self._socket is not None:
                    self._socket.setsockopt(zmq.RCVTIMEO, int(self.timeout * 1000))
        if reply.get("ok"):
            return reply.get("value")
        name, message = reply.get("error", "DeviceError"), reply.get("message", "")
        raise ERRORS.get(name, DeviceRefusedError)(f"{self.device} {verb}: {message}")

    def run(self, verb: str, *args: Any, poll: float = 0.02, timeout: float = 120.0) -> Any:
        """A blocking verb: submit it, poll its job until it ends (each poll kicks the watchdog)."""
        job = self.call(verb, *args)["job"]
        end = time.monotonic() + timeout
        while True:
            state = self.call("result", job, poll, deadline=LOST_AFTER)  # held up to `poll` s by the server
            if state["done"]:
                self.note = state.get("note", "")
                return state["value"]
            if time.monotonic() > end:
                self.call_quietly("stopJ")
                raise TimeoutError(f"{self.device} {verb} did not finish within {timeout:g} s")

    def call_quietly(self, verb: str, *args: Any) -> None:
        try:
            self.call(verb, *args)
        except Exception:  # noqa: BLE001 - best effort (closing, stopping after a timeout)
            pass

    def _handshake_refused(self) -> bool:
        """The server turned this client's key away (a CURVE handshake failed on this socket)."""
        try:
            return bool(self._monitor.poll(0))
        except zmq.ZMQError:
            return False

    def close(self) -> None:
        with self._lock:
            if self._socket is not None:
                self._socket.disable_monitor()
                self._monitor.close(0)
                self._socket.close(0)
                self._socket = None


def open_client(config: NetDeviceConfig, kind: str) -> tuple[NetClient, dict]:
    """A connected client of the configured device and its hello: found with zeroconf when no
    address is given; a one-line error when the kind does not match."""
    keys = client_keys(config.keys)
    address, device = config.address, config.name or kind
    if address is None:
        from hardware.net.discovery import find

        found = find(kind, config.name, config.discovery_timeout)
        address, device = found.address, found.name
    client = NetClient(address, keys, device, config.timeout, config.session)
    try:
        hello = client.call("hello")
    except Exception:
        client.close()
        raise
    if hello.get("kind") != kind:
        client.close()
        raise ValueError(f"{device} at {address} is a {hello.get('kind')}, not a {kind}")
    return client, hello


class _NetDevice:
    """The connect/disconnect half shared by the networked devices."""

    kind = ""

    def _connect(self) -> None:
        self._client, self.hello = open_client(self.config, self.kind)
        self._on_connect()

    def _on_connect(self) -> None:
        pass

    def _disconnect(self) -> None:
        self._client.call_quietly("release")
        self._client.close()

    def _call(self, verb: str, *args: Any) -> Any:
        self.require_connected()
        return self._client.call(verb, *args)

    def _run(self, verb: str, *args: Any) -> Any:
        self.require_connected()
        return self._client.run(verb, *args, poll=self.config.poll, timeout=self.config.motion_timeout)


class NetArm(_NetDevice, Arm):
    """A UR-style arm served by `nift serve` (ur_rtde's verbs, plus setWatchdog / kickWatchdog)."""

    kind = "arm"

    def __init__(self, config: NetDeviceConfig = NetDeviceConfig()) -> None:
        Arm.__init__(self, config)
        self._limits: JointLimits | None = None

    def _on_connect(self) -> None:
        r = self._client.call("joint_limits")
        self._limits = JointLimits(*(np.asarray(r[k], float) for k in ("lower", "upper", "velocity", "acceleration", "jerk")))

    @property
    def joint_limits(self) -> JointLimits:
        self.require_connected()
        return self._limits

    def getActualQ(self) -> np.ndarray:
        return np.asarray(self._call("getActualQ"), float)

    def getActualQd(self) -> np.ndarray:
        return np.asarray(self._call("getActualQd"), float)

    def getTimestamp(self) -> float:
        return float(self._call("getTimestamp"))

    def getActualTCPPose(self) -> np.ndarray:
        return np.asarray(self._call("getActualTCPPose"), float)

    def setTcp(self, tcp_offset: np.ndarray) -> None:
        self._call("setTcp", np.asarray(tcp_offset, float))

    def getTCPOffset(self) -> np.ndarray:
        return np.asarray(self._call("getTCPOffset"), float)

    def getForwardKinematics(self, q: np.ndarray | None = None) -> np.ndarray:
        return np.asarray(self._call("getForwardKinematics", None if q is None else np.asarray(q, float)), float)

    def moveJ(self, q: np.ndarray, speed: float = 1.05, acceleration: float = 1.4) -> bool:
        return bool(self._run("moveJ", np.asarray(q, float), float(speed), float(acceleration)))

    def moveL(self, pose: np.ndarray, speed: float = 0.25, acceleration: float = 1.2) -> bool:
        return bool(self._run("moveL", np.asarray(pose, float), float(speed), float(acceleration)))

    def executeTrajectory(self, times: np.ndarray, q: np.ndarray, qd: np.ndarray | None = None) -> bool:
        return bool(self._run("executeTrajectory", np.asarray(times, float), np.asarray(q, float),
                              None if qd is None else np.asarray(qd, float)))

    def stopJ(self, deceleration: float = 2.0) -> None:
        self._call("stopJ", float(deceleration))

    def isProtectiveStopped(self) -> bool:
        return bool(self._call("isProtectiveStopped"))

    def unlockProtectiveStop(self) -> None:
        self._call("unlockProtectiveStop")

    def getActualTCPForce(self) -> np.ndarray:
        return np.asarray(self._call("getActualTCPForce"), float)

    def startContactDetection(self, force: float | None = None) -> bool:
        return bool(self._call("startContactDetection", None if force is None else float(force)))

    def readContactDetection(self) -> bool:
        return bool(self._call("readContactDetection"))

    def stopContactDetection(self) -> bool:
        return bool(self._call("stopContactDetection"))

    def teachMode(self) -> bool:
        return bool(self._call("teachMode"))

    def endTeachMode(self) -> bool:
        return bool(self._call("endTeachMode"))

    def isTeachMode(self) -> bool:
        return bool(self._call("isTeachMode"))

    def getLastError(self) -> str:
        note = getattr(self._client, "note", "")
        return note or str(self._call("getLastError"))

    def setWatchdog(self, min_frequency: float = 10.0) -> None:
        """While a motion runs the server stops the arm if this client sends nothing for 1 / min_frequency s."""
        self._call("setWatchdog", float(min_frequency))

    def kickWatchdog(self) -> None:
        self._call("kickWatchdog")


class NetGripper(_NetDevice, Gripper):
    """A two-finger gripper served by `nift serve`."""

    kind = "gripper"

    def __init__(self, config: NetDeviceConfig = NetDeviceConfig()) -> None:
        Gripper.__init__(self, config)

    def _on_connect(self) -> None:
        self._stroke, self._max_force = float(self._client.call("stroke")), float(self._client.call("max_force"))

    @property
    def stroke(self) -> float:
        self.require_connected()
        return self._stroke

    @property
    def max_force(self) -> float:
        self.require_connected()
        return self._max_force

    def open(self, speed: float = 0.1, width: float | None = None) -> None:
        self._run("open", float(speed), None if width is None else float(width))

    def close(self, force: float = 40.0, speed: float = 0.05) -> bool:
        return bool(self._run("close", float(force), float(speed)))

    @property
    def width(self) -> float:
        return float(self._call("width"))

    @property
    def object_detected(self) -> bool:
        return bool(self._call("object_detected"))

    @property
    def force(self) -> float:
        return float(self._call("force"))


class NetCamera(_NetDevice, DepthCamera):
    """An RGB-D camera served by `nift serve`."""

    kind = "camera"

    def __init__(self, config: NetDeviceConfig = NetDeviceConfig()) -> None:
        DepthCamera.__init__(self, config)

    def _on_connect(self) -> None:
        self._intrinsics = CameraIntrinsics(**self._client.call("intrinsics"))

    @property
    def intrinsics(self) -> CameraIntrinsics:
        self.require_connected()
        return self._intrinsics

    def capture(self) -> Frame:
        r = self._run("capture")
        return Frame(r["color"], r["depth"], CameraIntrinsics(**r["intrinsics"]), float(r["timestamp"]))
