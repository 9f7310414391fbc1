"""`nift serve`: the simulated cell's devices as network services, advertised with zeroconf."""
from __future__ import annotations

import argparse
import ipaddress
import json
import logging
import signal
import sys
from pathlib import Path

from app.console.options import add_config_argument

NAME = "serve"
HELP = "serve the simulated cell's arm, gripper, camera and test rig on the network (hardware-in-the-loop)"
DEVICES = ("arm", "gripper", "camera", "sim")


def add_arguments(p: argparse.ArgumentParser) -> None:
    from hardware.net.keys import DEFAULT_KEY_DIR

    p.add_argument("--devices", default=",".join(DEVICES),
                   help=f"comma list of what to serve, of {', '.join(DEVICES)} (sim: the test rig that spawns and judges objects)")
    p.add_argument("--bind", default="127.0.0.1",
                   help="address to listen and advertise on (default loopback; every connection is CURVE-encrypted either way)")
    p.add_argument("--port", type=int, default=0, help="TCP port (default: a free one, found by clients through zeroconf)")
    p.add_argument("--keys", type=Path, default=DEFAULT_KEY_DIR,
                   help=f"folder of the CURVE keys, made if missing (default {DEFAULT_KEY_DIR}; docs/security.md)")
    p.add_argument("--make-keys", action="store_true", help="make what is missing of the --keys folder, print it, and exit")
    p.add_argument("--add-client", type=Path, metavar="FILE",
                   help="allow the client whose public key file (its client.key) is given, and exit")
    p.add_argument("--name", default="nift-sim", help="prefix of the advertised device names (NAME-arm, ...)")
    p.add_argument("--realtime", action="store_true", help="pace the physics to the wall clock, as a real controller moves")
    p.add_argument("--watchdog", type=float, default=0.5,
                   help="seconds of silence from its client after which a running arm motion is stopped")
    p.add_argument("--seed", type=int, default=0, help="camera noise seed (each job reseeds it from its own seed)")
    p.add_argument("--json", action="store_true", help="print the serving line as JSON (devices, address, key folder)")
    p.add_argument("--no-advertise", action="store_true", help="do not announce the devices with zeroconf")
    add_config_argument(p)


def _devices(text: str) -> list[str]:
    names = [d.strip() for d in text.split(",") if d.strip()]
    unknown = [d for d in names if d not in DEVICES]
    if unknown or not names:
        raise ValueError(f"--devices {text!r}: choose from {', '.join(DEVICES)}")
    return names


def check_bind(bind: str) -> None:
    """An IPv4 address (discovery announces on IPv4 only), or localhost."""
    try:
        address = None if bind == "localhost" else ipaddress.ip_address(bind)
    except ValueError:
        raise ValueError(f"--bind {bind!r} is not an IP address") from None
    if address is not None and address.version != 4:  # discovery announces on IPv4 only
        raise ValueError(f"--bind {bind}: an IPv4 address is needed (127.0.0.1 for this machine)")


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from app.console.options import cell_config
    from hardware.net.keys import make_keys, server_keys
    from hardware.net.server import DeviceServer, ServerConfig, check_settings

    if args.make_keys or args.add_client:
        return _keys(args)
    names = _devices(args.devices)
    check_bind(args.bind)
    config = cell_config(args)
    config = replace(config, world=replace(config.world, realtime=args.realtime))
    check_settings(args.port, args.watchdog)  # before the keys are written and the simulator is imported

    from app.simcell.cell import SimCell
    from app.simcell.rig import SimRig, rig_service
    from hardware.net.discovery import Advertiser
    from hardware.net.verbs import device_service

    _raise_descriptor_limit()
    made = make_keys(args.keys)  # on the first start only
    keys = server_keys(args.keys)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s nift serve: %(message)s", stream=sys.stderr)
    server_config = ServerConfig(keys=keys, bind=args.bind, port=args.port, watchdog=args.watchdog)
    signal.signal(signal.SIGTERM, _interrupt)  # a terminated server stops its arm and unregisters, as Ctrl-C does
    with SimCell(config) as cell:
        devices = {"arm": cell.arm, "gripper": cell.gripper, "camera": cell.camera}
        services = {f"{args.name}-{'rig' if d == 'sim' else d}": (rig_service(SimRig(cell)) if d == "sim" else
                                         device_service(d, devices[d], {"model": MODELS[d], "serial": f"{args.name}-{d}"}))
                    for d in names}
        server = DeviceServer(services, server_config)
        port = server.start()
        advertiser = None if args.no_advertise else Advertiser(args.bind)
        try:
            for name, svc in services.items():
                if advertiser:
                    advertiser.advertise(name, svc.kind, port, svc.properties)
            address = f"tcp://{args.bind}:{port}"
            print(json.dumps({"serving": list(services), "address": address, "keys": str(args.keys)}) if args.json
                  else f"serving {', '.join(services)} on {address} (CURVE keys in {args.keys}{', made now' if made else ''});"
                       " Ctrl-C stops", flush=True)
            server.serve_forever()
        except KeyboardInterrupt:
            pass
        finally:
            if advertiser:
                advertiser.close()
            server.close()
    _exit_now()
    return 0


def _exit_now() -> None:
    """End the process now that every device is stopped, the socket closed and the cell disconnected:
    the interpreter's own teardown of torch and Open3D (about 0.8 s here) would hold a stopped server
    past its 1 s; nothing is left to flush but the standard streams and the log."""
    import os

    logging.shutdown()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


def _raise_descriptor_limit(most: int = 65536) -> None:
    """Let the server hold as many connections as the system allows this process (the soft limit up to
    the hard one): a stranger's connections are dropped after the handshake interval, meanwhile they
    must not starve the clients."""
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    want = most if hard == resource.RLIM_INFINITY else min(hard, most)
    if soft < want:
        resource.setrlimit(resource.RLIMIT_NOFILE, (want, hard))


def _keys(args: argparse.Namespace) -> int:
    """--make-keys / --add-client: the key folder's files, made or allowed, printed."""
    from hardware.net.keys import add_client, make_keys, public_key

    if args.add_client:
        public_key(args.add_client)  # a key file, or one line before anything is written
    made = make_keys(args.keys)
    for path in made:
        print(f"made {path}")
    if args.add_client:
        print(f"allowed {add_client(args.keys, args.add_client)} (a running nift serve reads it at its next start)")
    elif not made:
        print(f"{args.keys} already holds the keys")
    return 0


def _interrupt(*_) -> None:
    raise KeyboardInterrupt


MODELS = {"arm": "UR5 (PyBullet)", "gripper": "two-finger (PyBullet)", "camera": "Kinect v2 (PyBullet)"}
