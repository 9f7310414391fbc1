"""Advertising and finding the devices with python-zeroconf (mDNS / DNS-SD).

Each served device is one service, `NAME._nift-KIND._tcp.local.`, whose properties say its kind,
model, serial and protocol version. By default both sides use the loopback interface only, so
nothing is announced beyond this machine; a server bound to another address advertises there.
"""
from __future__ import annotations

import socket
import time
from dataclasses import dataclass

from zeroconf import IPVersion, ServiceBrowser, ServiceInfo, ServiceListener, Zeroconf

from hardware.net.wire import PROTOCOL

KINDS = ("arm", "gripper", "camera", "sim")


class DeviceNotFoundError(ConnectionError):
    """No advertised device matched what was looked for."""


def service_type(kind: str) -> str:
    return f"_nift-{kind}._tcp.local."


@dataclass(frozen=True)
class Found:
    """A device seen on the network."""

    name: str
    kind: str
    address: str  # tcp://HOST:PORT
    properties: dict[str, str]


def _host(address: str) -> str:
    """The IPv4 address to announce on and advertise for a bind address (loopback for the names of it)."""
    return "127.0.0.1" if address in ("localhost", "0.0.0.0") else address


class Advertiser:
    """Announces devices until closed."""

    def __init__(self, address: str = "127.0.0.1") -> None:
        self.address = _host(address)
        self._zc = Zeroconf(interfaces=[self.address], ip_version=IPVersion.V4Only)
        self._infos: list[ServiceInfo] = []

    def advertise(self, name: str, kind: str, port: int, properties: dict[str, str]) -> None:
        props = {"kind": kind, "protocol": str(PROTOCOL), **properties}
        info = ServiceInfo(service_type(kind), f"{name}.{service_type(kind)}", port=port, properties=props,
                           addresses=[socket.inet_aton(self.address)], server=f"{name}.local.")
        self._zc.register_service(info)
        self._infos.append(info)

    def close(self) -> None:
        for info in self._infos:
            self._zc.unregister_service(info)
        self._zc.close()


class _Collect(ServiceListener):
    def __init__(self) -> None:
        self.names: list[tuple[str, str]] = []

    def add_service(self, zc: Zeroconf, type_: str, name: str) -> None:
        self.names.append((type_, name))

    def update_service(self, zc: Zeroconf, type_: str, name: str) -> None:
        pass

    def remove_service(self, zc: Zeroconf, type_: str, name: str) -> None:
        pass


def browse(kinds: tuple[str, ...] = KINDS, timeout: float = 2.0, interface: str = "127.0.0.1",
           until=None) -> list[Found]:
    """The devices of these kinds advertised within `timeout` s (`until(found)`: stop early once true)."""
    zc = Zeroconf(interfaces=[_host(interface)], ip_version=IPVersion.V4Only)
    listener = _Collect()
    browsers = [ServiceBrowser(zc, service_type(k), listener) for k in kinds]
    found: dict[str, Found] = {}
    end = time.monotonic() + timeout
    try:
        while True:
            for type_, name in list(listener.names):
                if name not in found and (info := zc.get_service_info(type_, name, timeout=500)) is not None:
                    props = {k.decode(): (v or b"").decode() for k, v in info.properties.items()}
                    found[name] = Found(name.removesuffix("." + type_), props.get("kind", ""),
                                        f"tcp://{info.parsed_addresses()[0]}:{info.port}", props)
            if time.monotonic() > end or (until is not None and until(list(found.values()))):
                break
            time.sleep(0.05)
    finally:
        for b in browsers:
            b.cancel()
        zc.close()
    return sorted(found.values(), key=lambda f: (f.kind, f.name))


def find(kind: str, name: str | None = None, timeout: float = 3.0, interface: str = "127.0.0.1") -> Found:
    """The advertised device of this kind (and name), or DeviceNotFoundError naming what was looked for and found."""
    def match(f: Found) -> bool:
        return f.kind == kind and (name is None or f.name == name)

    found = browse((kind,), timeout, interface, until=lambda fs: any(match(f) for f in fs))
    hits = [f for f in found if match(f)]
    if not hits:
        article = "an" if kind[0] in "aeiou" else "a"
        wanted = f"{article} {kind} named {name!r}" if name else f"{article} {kind}"
        seen = ", ".join(f"{f.name} ({f.kind})" for f in found) or "nothing"
        raise DeviceNotFoundError(f"looked for {wanted} on the network for {timeout:g} s; found {seen} (is `nift serve` running?)")
    return hits[0]
