"""The `nift` command (placeholder until the verbs land)."""
import argparse
from app import __version__
def main(argv=None):
    p = argparse.ArgumentParser(prog="nift"); p.add_argument("--version", action="version", version=__version__)
    p.parse_args(argv)
