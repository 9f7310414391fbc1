"""Record demos through the teach page, as a careful operator would: headless Chromium types the
scripted teacher's poses into the page for the instances of the first N scripted demos, so the two
demo sets differ only in how they were taught (docs/teach.md compares their templates with nift bench).

    .venv/bin/python scripts/page_demos.py --out out/page-demos --demos 3
"""
from __future__ import annotations

import argparse
import socket
import sys
from pathlib import Path

import numpy as np

from app.sim.cell import CellConfig, SimCell
from app.tasks.demo import DEMO_GLOB, load_demo
from app.tasks.library import DEMOS_DIR
from app.tasks.task import task
from app.teach.operator import Operator, chromium
from app.teach.page import TeachPage
from app.teach.session import TeachSession


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def record(name: str, out: Path, count: int) -> list[str]:
    """Teach `count` demos of a task through the page into out/<task>; the page's last answer per demo."""
    t = task(name)
    instances = [load_demo(p).seed for p in sorted((DEMOS_DIR / t.demos).glob(DEMO_GLOB))[:count]]
    with SimCell(CellConfig()) as cell:
        session = TeachSession(cell, t, out / t.name, np.array(cell.camera.config.T_base_cam))
        page = TeachPage(session, "127.0.0.1", free_port())
        driver = chromium()
        try:
            operator = Operator(page, driver)
            operator.open()
            return [operator.teach_one(instance)[-1] for instance in instances]
        finally:
            driver.quit()
            page.stop()
            session.close()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="directory whose <task>/ folders receive the demos")
    parser.add_argument("--demos", type=int, default=3, help="demos per task (default 3)")
    parser.add_argument("--tasks", default="mug,bowl,bottle")
    args = parser.parse_args()
    if (args.out).exists() and any(args.out.iterdir()):
        sys.exit(f"page_demos: --out {args.out} is not empty; choose a new directory")
    for name in args.tasks.split(","):
        for line in record(name, args.out, args.demos):
            print(f"{name}: {line}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
