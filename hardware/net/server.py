"""`DeviceServer`: devices behind one ZeroMQ ROUTER socket.

The socket is a CURVE server (`hardware.net.keys`): a client whose public key is not in the allowed
list fails the handshake in ZeroMQ's authenticator, so none of its bytes reach this code, and every
connection is encrypted with its own session keys (a captured session replayed is not a handshake).
Every request is then checked for its shape (`hardware.net.request`: no field is used before) and
before it reaches a device (`hardware.net.checks`, in the verb tables of `hardware.net.verbs`); a
malformed or oversized message gets an error reply and the server keeps serving. A client is its
key and the session it names, so no key can speak for another's session.

One client commands a device at a time: the first to send it a command holds it until it says
"release" or stays silent for `lease` seconds with nothing running; another client may read its
state, and stop it, but not command it. Motions run on one motion thread (the simulated
devices share one physics world), and while a client commands an arm, another client's motion or
capture is refused Busy rather than queued behind its motions; the socket keeps answering: state reads,
"result" polls and stopJ. A watchdog (ur_rtde's setWatchdog/kickWatchdog) stops a running arm
motion when its client has sent nothing for 1 / min_frequency seconds; any message is a kick, and
a waiting client's "result" polls keep it fed (each waits up to MAX_WAIT for its job, so the reply
comes the moment the motion ends).
"""
from __future__ import annotations

import itertools
import logging
import threading
import time
from concurrent import futures
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import zmq
import zmq.auth
from zmq.auth.thread import ThreadAuthenticator

from hardware.net import wire
from hardware.net.keys import ServerKeys, as_server
from hardware.net.request import parse
from hardware.net.verbs import Service

LOG = logging.getLogger("nift.net")
BUILTIN = ("hello", "result", "release", "setWatchdog", "kickWatchdog")
DRAIN = 64  # requests answered in a row before the watchdog looks again
KEPT_RESULTS = 256  # finished jobs remembered for their "result" poll
CLOSE_WAIT = 0.3  # s a closing server waits for its running jobs after stopping their devices
HANDSHAKE_MS = 2000  # a TCP connection that has not completed the CURVE handshake by then is dropped
QUEUED_REPLIES = 64  # replies kept per client that does not read them (ZeroMQ's high-water mark)
MAX_WAIT = 0.02  # s a "result" poll may wait for its job: it answers the moment the job ends, and other
# requests (stopJ, state reads) wait at most this long behind it


@dataclass(frozen=True)
class ServerConfig:
    """Where the server listens and how it guards its devices."""

    keys: ServerKeys
    bind: str = "127.0.0.1"
    port: int = 0  # 0: a free port, chosen at start
    watchdog: float = 0.5  # s: default silence after which a running arm motion is stopped
    lease: float = 10.0  # s: a silent commanding client with nothing running gives up control

    def __post_init__(self) -> None:
        check_settings(self.port, self.watchdog, self.lease)


def check_settings(port: int, watchdog: float, lease: float = 10.0) -> None:
    """A one-line error for a port, watchdog or lease out of range (before any key is written)."""
    if not 0 <= port <= 65535:
        raise ValueError(f"--port must be in [0, 65535], got {port}")
    if not 0.0 < watchdog <= 60.0:
        raise ValueError(f"--watchdog must be in (0, 60] s, got {watchdog}")
    if not 0.0 < lease <= 3600.0:
        raise ValueError(f"lease must be in (0, 3600] s, got {lease}")


class AllowedKeys:
    """The client public keys in a folder (read at start): zmq.auth asks it about each handshake."""

    def __init__(self, folder) -> None:
        self.folder = folder
        self.keys = set(zmq.auth.load_certificates(str(folder)))  # z85 public keys

    def callback(self, domain: str, key: bytes) -> bool:
        """Whether the client holding public key `key` (z85) may connect; a refusal is logged."""
        allowed = key in self.keys
        if not allowed:
            LOG.warning("refused a connection: client key %s... is not in %s", key[:8].decode(errors="replace"), self.folder)
        return allowed


class Refused(Exception):
    """A request the server will not carry out: (error name, message)."""

    def __init__(self, name: str, message: str) -> None:
        super().__init__(message)
        self.name = name


@dataclass
class _Job:
    future: Future
    device: str
    client: str
    note: str = ""  # why the server stopped it (watchdog)


@dataclass
class _Control:
    client: str
    since: float
    watchdog: float


@dataclass
class DeviceServer:
    """Serves `services` ({name: Service}) until `stop()`; `port` is known after `start()`."""

    services: dict[str, Service]
    config: ServerConfig
    port: int = 0
    _seen: dict[str, float] = field(default_factory=dict)
    _control: dict[str, _Control] = field(default_factory=dict)
    _jobs: dict[int, _Job] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self._ids = itertools.count(1)
        self._stop = threading.Event()
        self._context = zmq.Context()  # its own: one authenticator per context
        self._auth: ThreadAuthenticator | None = None
        self._socket: zmq.Socket | None = None
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="nift-motion")

    # lifecycle ---------------------------------------------------------------------------------
    def start(self) -> int:
        """Bind the socket; the port it listens on."""
        self._auth = ThreadAuthenticator(self._context, log=LOG.getChild("auth"))
        self._auth.start()
        self._auth.configure_curve_callback(domain="*", credentials_provider=AllowedKeys(self.config.keys.clients))
        s = self._context.socket(zmq.ROUTER)
        as_server(s, self.config.keys)
        s.setsockopt(zmq.LINGER, 0)
        s.setsockopt(zmq.MAXMSGSIZE, 4 * wire.MAX_MESSAGE)  # far larger: the peer is cut off, never buffered
        s.setsockopt(zmq.HANDSHAKE_IVL, HANDSHAKE_MS)  # a connection that has not authenticated by then is closed
        s.setsockopt(zmq.SNDHWM, QUEUED_REPLIES)  # replies a client leaves unread: the rest are dropped, not kept
        try:
            if self.config.port:
                s.bind(f"tcp://{self.config.bind}:{self.config.port}")
                self.port = self.config.port
            else:
                self.port = s.bind_to_random_port(f"tcp://{self.config.bind}")
        except zmq.ZMQError as exc:
            s.close(0)
            raise OSError(f"cannot listen on {self.config.bind} port {self.config.port or 'any'}: {exc}") from None
        self._socket = s
        LOG.info("serving %s on %s:%d", ", ".join(self.services), self.config.bind, self.port)
        return self.port

    def stop(self) -> None:
        """Ask `serve_forever` to return."""
        self._stop.set()

    def close(self) -> None:
        """Stop every device that moves, close the socket, end the motion thread: a job still running
        CLOSE_WAIT s after its devices were stopped (a rig's calibration goes on to its next view) is
        left to the process's end, so a stopped server never waits on it."""
        for name, svc in self.services.items():
            if "stopJ" in svc.verbs and self._running(name):
                self._safe_stop(name, "server shutting down")
        running = [j.future for j in self._jobs.values() if not j.future.done()]
        self._worker.shutdown(wait=False, cancel_futures=True)
        futures.wait(running, timeout=CLOSE_WAIT)
        if self._socket is not None:
            self._socket.close(0)
            self._socket = None
        if self._auth is not None:
            self._auth.stop()
            self._auth = None
        self._context.term()  # its own: nothing else uses it

    def serve_forever(self, poll_ms: int = 10) -> None:
        """Answer requests until `stop()`; check the watchdog between them."""
        if self._socket is None:
            self.start()
        poller = zmq.Poller()
        poller.register(self._socket, zmq.POLLIN)
        while not self._stop.is_set():
            if poller.poll(poll_ms):
                self._drain()
            self._watch()

    def _drain(self, most: int = DRAIN) -> None:
        """Answer the requests waiting (at most `most`) before the watchdog looks: a client whose
        messages queued while this server was busy has not been silent."""
        for _ in range(most):
            try:
                frames = self._socket.recv_multipart(zmq.NOBLOCK, copy=False)
            except zmq.Again:
                return
            self._answer(frames)

    # one request -------------------------------------------------------------------------------
    def _answer(self, frames: list[zmq.Frame]) -> None:
        if len(frames) < 2:
            return  # no return address: nothing can be answered
        head, payload = frames[:-1], frames[-1]
        try:
            reply = wire.reply_ok(self._handle(payload.bytes, payload.get("User-Id")))
        except Refused as r:
            reply = wire.reply_error(r.name, str(r))
        except wire.WireError as exc:
            LOG.warning("malformed request refused: %s", exc)
            reply = wire.reply_error("WireError", str(exc))
        except Exception as exc:  # noqa: BLE001 - no request may end the serve loop: logged, answered
            LOG.exception("request failed inside the server")
            reply = wire.reply_error("InternalError", f"the server failed on this request ({type(exc).__name__})")
        try:
            self._socket.send_multipart([*head, reply])
        except zmq.ZMQError as exc:
            LOG.warning("reply not sent: %s", exc)

    def _handle(self, payload: bytes, key: str) -> Any:
        """The value of one request from the client holding CURVE key `key` (z85, set by the authenticator)."""
        request = parse(wire.unpack(payload))  # the shape first: no field is used before it is checked
        client = f"{key[:8]}/{request.client}"
        if request.v != wire.PROTOCOL:
            raise Refused("ProtocolError", f"protocol version {request.v}; this server speaks {wire.PROTOCOL}")
        device, verb, args = self._resolve(request.device), request.verb, request.args
        if device not in self.services:
            raise Refused("UnknownDevice", f"no device {device[:40]!r} here (serving: {', '.join(self.services)})")
        self._seen[client] = time.monotonic()
        if verb in BUILTIN:
            return self._builtin(client, device, verb, args)
        svc = self.services[device]
        spec = svc.verbs.get(verb)  # a string: the request's schema says so
        if spec is None:
            raise Refused("UnknownVerb", f"{svc.kind} {device!r} has no verb {verb[:40]!r}")
        if len(args) > spec.most_args:
            raise Refused("ValueError", f"{verb} takes at most {spec.most_args} arguments, got {len(args)}")
        if spec.kind in ("command", "motion"):
            for name in (device, *self._moved(device)):  # all or none: each checked before any is taken
                self._check_claim(client, name)
            for name in (device, *self._moved(device)):
                self._claim(client, name)
        if spec.kind in ("motion", "work"):
            self._check_motion_thread(client, device, verb)
            return {"job": self._submit(client, device, lambda: spec.call(svc.device, args))}
        return self._call(lambda: spec.call(svc.device, args))

    def _check_motion_thread(self, client: str, device: str, verb: str) -> None:
        """Busy while another client commands an arm (or a rig that moves one), its lease live: the served
        devices share one motion thread (one physics world), and a capture queued there (~0.1 s each)
        would stretch that client's motions. A camera's or gripper's commander blocks no one."""
        for name, svc in self.services.items():
            if (svc.watchdog or svc.moves) and self._held_by_other(client, name) is not None:
                raise Refused("Busy", f"{device} {verb[:40]}: another client commands {name} "
                                      f"(read state, or last_frame, meanwhile)")

    def _resolve(self, device: Any) -> Any:
        """A device's name, or its kind when exactly one device of that kind is served."""
        if device in self.services:
            return device
        named = [n for n, svc in self.services.items() if svc.kind == device]
        return named[0] if len(named) == 1 else device

    def _builtin(self, client: str, device: str, verb: str, args: list) -> Any:
        svc = self.services[device]
        if verb == "hello":
            return {"kind": svc.kind, "protocol": wire.PROTOCOL, "properties": svc.properties,
                    "controlled_by_other": device in self._control and self._control[device].client != client}
        if verb == "result":
            return self._result(client, args[0] if args else None, args[1] if len(args) > 1 else 0.0)
        if verb == "release":
            if device in self._control and self._control[device].client == client:
                del self._control[device]
                self._reset(device)
            return None
        if verb == "kickWatchdog":
            return None
        # setWatchdog(min_frequency): the client must talk at least this often while its motion runs
        if not svc.watchdog:
            raise Refused("UnknownVerb", f"{svc.kind} {device!r} has no watchdog")
        freq = args[0] if args else None
        if isinstance(freq, bool) or not isinstance(freq, (int, float)) or not 0.1 <= freq <= 1000:
            raise Refused("ValueError", f"setWatchdog needs a minimum frequency in [0.1, 1000] Hz, got {freq!r}")
        self._claim(client, device)
        self._control[device].watchdog = 1.0 / float(freq)
        return None

    # control, jobs, watchdog -------------------------------------------------------------------
    def _moved(self, device: str) -> list[str]:
        """The other served devices a device's motions move (`Service.moves`)."""
        kinds = self.services[device].moves
        return [name for name, svc in self.services.items() if name != device and svc.kind in kinds]

    def _check_claim(self, client: str, device: str) -> None:
        """Busy unless `client` may command `device` now."""
        held = self._held_by_other(client, device)
        if held is not None:
            LOG.warning("refused %r commanding %s: client %r commands it", client[:40], device, held.client[:40])
            raise Refused("Busy", f"{device} is commanded by another client ({held.client[:40]}, for "
                                  f"{time.monotonic() - held.since:.1f} s); a second client may read it but not command it")

    def _held_by_other(self, client: str, device: str) -> _Control | None:
        """Another client's hold on `device` while it lasts: a job of its runs, or it spoke within the lease."""
        held = self._control.get(device)
        if held is None or held.client == client:
            return None
        silent = time.monotonic() - self._seen.get(held.client, 0.0)
        return held if self._running(device) or silent < self.config.lease else None

    def _claim(self, client: str, device: str) -> None:
        self._check_claim(client, device)
        held = self._control.get(device)
        if held is not None and held.client != client:
            LOG.info("%s: control passes from silent client %r to %r", device, held.client[:40], client[:40])
            self._reset(device)
            held = None
        if held is None:
            self._control[device] = _Control(client, time.monotonic(), self.config.watchdog)

    def _submit(self, client: str, device: str, work) -> int:
        job_id = next(self._ids)
        self._jobs[job_id] = _Job(self._worker.submit(self._call, work), device, client)
        done = [k for k, j in self._jobs.items() if j.future.done()]
        for k in done[:-KEPT_RESULTS]:
            del self._jobs[k]
        return job_id

    def _reset(self, device: str) -> None:
        """The device's per-client settings put back (`Service.reset`) when its commander lets go."""
        reset = self.services[device].reset
        if reset is not None:
            self._call(lambda: reset(self.services[device].device))

    def _result(self, client: str, job_id: Any, wait: Any = 0.0) -> dict:
        """A job's outcome, to the client whose job it is, waiting for it up to `wait` s (at most
        MAX_WAIT: the socket is not answered meanwhile)."""
        job = self._jobs.get(job_id) if isinstance(job_id, int) and not isinstance(job_id, bool) else None
        if job is None or job.client != client:  # another client's job is not shown to exist
            raise Refused("ValueError", f"no job {str(job_id)[:20]} of this client on this server")
        if isinstance(wait, (int, float)) and not isinstance(wait, bool) and wait > 0:
            futures.wait([job.future], timeout=min(float(wait), MAX_WAIT))
        if not job.future.done():
            return {"done": False}
        del self._jobs[job_id]
        error = job.future.exception()
        if isinstance(error, Refused):
            raise error
        return {"done": True, "value": job.future.result(), "note": job.note}

    def _running(self, device: str) -> bool:
        """A job runs on the device, or on a device whose motions move it (a rig's, for the arm)."""
        return any(not j.future.done() and (j.device == device or device in self._moved(j.device))
                   for j in self._jobs.values())

    def _watch(self) -> None:
        now = time.monotonic()
        for job in list(self._jobs.values()):
            svc = self.services[job.device]
            if job.future.done() or job.note or not (svc.watchdog or svc.moves):
                continue
            control = self._control.get(job.device)
            limit = control.watchdog if control else self.config.watchdog
            silent = now - self._seen.get(job.client, 0.0)
            if silent > limit:
                job.note = f"watchdog: no message from the client for {silent:.2f} s (limit {limit:.2f} s); arm stopped"
                self._safe_stop(job.device, job.note)

    def _safe_stop(self, device: str, why: str) -> None:
        """stopJ on the device, or on the devices its motions move (a rig has no stopJ of its own)."""
        LOG.warning("%s: %s", device, why)
        for name in [device] if "stopJ" in self.services[device].verbs else self._moved(device):
            if "stopJ" not in self.services[name].verbs:
                continue
            try:
                self.services[name].device.stopJ()
            except Exception:  # noqa: BLE001 - a failing stop is logged; the server keeps serving
                LOG.exception("%s: stopJ failed", name)

    @staticmethod
    def _call(work) -> Any:
        """Run a device call; what it raises becomes an error reply naming its type."""
        try:
            return work()
        except Refused:
            raise
        except ValueError as exc:
            raise Refused("ValueError", str(exc)) from None
        except Exception as exc:  # noqa: BLE001 - a device's error goes back to the client by name
            name = type(exc).__name__
            if name not in ("ProtectiveStopError", "DeviceNotConnectedError", "TimeoutError"):
                LOG.exception("device call failed")
                name = "DeviceError"
            raise Refused(name, str(exc)) from None
