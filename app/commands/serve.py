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
    from hardware.net.token import DEFAULT_TOKEN_FILE

    p.add_argument("--devices", default=",".join(DEVICES),
                   help=f"comma list of what to serve, of {', '.join(DEVICES)} (sim: the test rig that spawns and judges objects)")
    p.add_argument("--bind", default="127.0.0.1",
                   help="address to listen and advertise on (default loopback; any other needs an explicit --token-file)")
    p.add_argument("--port", type=int, default=0, help="TCP port (default: a free one, found by clients through zeroconf)")
    p.add_argument("--token-file", type=Path, help=f"shared token, mode 0600, written if missing (default {DEFAULT_TOKEN_FILE})")
    p.add_argument("--name", default="nift-sim", help="prefix of the advertised device names (NAME-arm, ...)")
    p.add_argument("--realtime", action="store_true", help="pace the physics to the wall clock, as a real controller moves")
    p.add_argument("--watchdog", type=float, default=0.5,
                   help="seconds of silence from its client after which a running arm motion is stopped")
    p.add_argument("--seed", type=int, default=0, help="camera noise seed (each job reseeds it from its own seed)")
    p.add_argument("--json", action="store_true", help="print the serving line as JSON (devices, address, token file)")
    p.add_argument("--no-advertise", action="store_true", help="do not announce the devices with zeroconf")
    add_config_argument(p)


def _devices(text: str) -> list[str]:
    names = [d.strip() for d in text.split(",") if d.strip()]
    unknown = [d for d in names if d not in DEVICES]
    if unknown or not names:
        raise ValueError(f"--devices {text!r}: choose from {', '.join(DEVICES)}")
    return names


def check_bind(bind: str, token_file: Path | None) -> None:
    """Loopback, or another address with an explicit token file."""
    try:
        address = None if bind == "localhost" else ipaddress.ip_address(bind)
    except ValueError:
        raise ValueError(f"--bind {bind!r} is not an IP address") from None
    if address is not None and address.version != 4:  # discovery announces on IPv4 only
        raise ValueError(f"--bind {bind}: an IPv4 address is needed (127.0.0.1 for this machine)")
    loopback = address is None or address.is_loopback
    if not loopback and token_file is None:
        raise ValueError(f"--bind {bind} exposes the cell beyond this machine: give the shared token with --token-file too")


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from app.console.options import cell_config
    from hardware.net.server import DeviceServer, ServerConfig, check_settings

    names = _devices(args.devices)
    check_bind(args.bind, args.token_file)
    config = cell_config(args)
    config = replace(config, world=replace(config.world, realtime=args.realtime))
    check_settings(args.port, args.watchdog)  # before the token file is written and the simulator is imported

    from app.simcell.cell import SimCell
    from app.simcell.rig import SimRig, rig_service
    from hardware.net.discovery import Advertiser
    from hardware.net.token import DEFAULT_TOKEN_FILE, ensure_token
    from hardware.net.verbs import device_service

    token_file = args.token_file or DEFAULT_TOKEN_FILE
    token = ensure_token(token_file)  # written on the first start only
    logging.basicConfig(level=logging.INFO, format="%(asctime)s nift serve: %(message)s", stream=sys.stderr)
    server_config = ServerConfig(token=token, bind=args.bind, port=args.port, watchdog=args.watchdog)
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
            print(json.dumps({"serving": list(services), "address": address, "token_file": str(token_file)}) if args.json
                  else f"serving {', '.join(services)} on {address} (token in {token_file}); Ctrl-C stops", flush=True)
            server.serve_forever()
        except KeyboardInterrupt:
            pass
        finally:
            if advertiser:
                advertiser.close()
            server.close()
    return 0


def _interrupt(*_) -> None:
    raise KeyboardInterrupt


MODELS = {"arm": "UR5 (PyBullet)", "gripper": "two-finger (PyBullet)", "camera": "Kinect v2 (PyBullet)"}
