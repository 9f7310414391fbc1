"""`nift devices`: what is advertised on the network (zeroconf)."""
from __future__ import annotations

import argparse
import json

NAME = "devices"
HELP = "list the NIFT devices advertised on the network (zeroconf)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--timeout", type=float, default=2.0, help="seconds to listen")
    p.add_argument("--interface", default="127.0.0.1", help="address of the interface to browse on (default loopback)")
    p.add_argument("--json", action="store_true", help="print JSON")


def run(args: argparse.Namespace) -> int:
    from hardware.net.discovery import browse

    if not 0.1 <= args.timeout <= 60:
        raise ValueError(f"--timeout must be in [0.1, 60] s, got {args.timeout}")
    found = browse(timeout=args.timeout, interface=args.interface)
    if args.json:
        print(json.dumps([f.__dict__ for f in found], indent=2))
    elif not found:
        print(f"no NIFT devices advertised on {args.interface} within {args.timeout:g} s")
    for f in found if not args.json else []:
        extra = ", ".join(f"{k} {v}" for k, v in f.properties.items() if k not in ("kind",))
        print(f"{f.name:24s} {f.kind:8s} {f.address:24s} {extra}")
    return 0
