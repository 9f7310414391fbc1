"""The `nift` command: one verb per module in app/commands (each has NAME, HELP, add_arguments, run)."""
from __future__ import annotations

import argparse
import os
import signal
import sys
import tempfile
import time
import traceback
from pathlib import Path

from app import __version__
from app.failures import CellFailure
from app.commands import (bench, bench_cell, bench_field, bench_geometry, bench_imitation, bench_jobs, bench_net,
                          calibrate, capture, devices, imitate, make_data, objects, run, serve, sim, teach, train)

COMMANDS = [run, objects, sim, serve, devices, calibrate, capture, make_data, train, teach, imitate, bench_geometry,
            bench_cell, bench_field, bench_imitation, bench_jobs, bench_net, bench]


class OneLineParser(argparse.ArgumentParser):
    """argparse, whose usage errors are one line on stderr (its usage text stays with --help), exit 2."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every verb registered."""
    parser = OneLineParser(prog="nift", description="NIFT cell: teach-by-demonstration pick-and-place.")
    parser.add_argument("--version", action="version", version=f"nift-cell {__version__}")
    verbs = parser.add_subparsers(dest="verb", metavar="VERB")
    for command in COMMANDS:
        sub = verbs.add_parser(command.NAME, help=command.HELP, description=command.HELP)
        command.add_arguments(sub)
        sub.set_defaults(run=command.run)
    return parser


# What a user's input or files can cause: one line and exit 2. OSError covers the paths a user gives
# (a directory where a file goes, a file where a directory goes, no permission, a full disk).
EXPECTED = (ValueError, OSError, CellFailure)  # bad input, a file, or what the cell could not do


def log_dir() -> Path:
    """Where the traceback of an unexpected error is written ($NIFT_LOG_DIR, default the temp dir)."""
    return Path(os.environ.get("NIFT_LOG_DIR") or Path(tempfile.gettempdir()) / "nift-logs")


def write_log(verb: str) -> Path:
    """The current exception's traceback in a new log file; its path."""
    directory = log_dir()
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"nift-{verb}-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}.log"
    path.write_text(f"nift {' '.join(sys.argv[1:])}\n{traceback.format_exc()}")
    return path


def main(argv: list[str] | None = None) -> int:
    """Entry point: parse, run the verb; an expected error becomes one line on stderr and exit 2, an
    unexpected one a line naming the log file that holds its traceback and exit 1."""
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # `nift ... | head` ends quietly
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "verb", None):
        parser.print_help()
        return 0
    try:
        return int(args.run(args) or 0)
    except EXPECTED as exc:
        print(f"nift {args.verb}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"nift {args.verb}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # noqa: BLE001 - a bug of ours: one line, the traceback in a file
        print(f"nift {args.verb}: internal error: {type(exc).__name__}: {exc} (traceback in {write_log(args.verb)})",
              file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
