"""The `nift` command: one verb per module in app/commands (each has NAME, HELP, add_arguments, run)."""
from __future__ import annotations

import argparse
import signal
import sys

from app import __version__
from app.commands import (bench, bench_cell, bench_field, bench_geometry, bench_imitation, bench_jobs, calibrate,
                          capture, imitate, make_data, objects, run, sim, teach, train)

COMMANDS = [run, objects, sim, calibrate, capture, make_data, train, teach, imitate, bench_geometry, bench_cell,
            bench_field, bench_imitation, bench_jobs, bench]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every verb registered."""
    parser = argparse.ArgumentParser(prog="nift", description="NIFT cell: teach-by-demonstration pick-and-place.")
    parser.add_argument("--version", action="version", version=f"nift-cell {__version__}")
    verbs = parser.add_subparsers(dest="verb", metavar="VERB")
    for command in COMMANDS:
        sub = verbs.add_parser(command.NAME, help=command.HELP, description=command.HELP)
        command.add_arguments(sub)
        sub.set_defaults(run=command.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point: parse, run the verb, turn expected errors into one line on stderr and exit 2."""
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # `nift ... | head` ends quietly
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "verb", None):
        parser.print_help()
        return 0
    try:
        return int(args.run(args) or 0)
    except (ValueError, FileNotFoundError) as exc:
        print(f"nift {args.verb}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
