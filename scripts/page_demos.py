"""Record demos through the teach page, as a careful operator would: headless Chromium types the
scripted teacher's poses into the page for the instances of the first N scripted demos (with
--same-places, also put down where those demos stood, so the Kinect sees the same side), and
docs/teach.md compares their templates with the scripted ones' with nift bench.

    .venv/bin/python scripts/page_demos.py --out out/page-demos --demos 3 [--same-places]
"""
from __future__ import annotations

import argparse
import socket
import sys
from pathlib import Path

import numpy as np

from app.simcell.cell import CellConfig, SimCell
from app.tasks.demo import DEMO_GLOB, load_demo
from app.tasks.demo_library import DEMOS_DIR
from app.tasks.task import task
from app.teach.operator import Operator, chromium
from app.teach.page import TeachPage
from app.teach.session import TeachSession


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def place_of(T_base_obj: np.ndarray) -> str:
    """'x y yaw' of an upright object's pose, as the page's "Put at" field takes it."""
    return f"{T_base_obj[0, 3]:.6f} {T_base_obj[1, 3]:.6f} {np.arctan2(T_base_obj[1, 0], T_base_obj[0, 0]):.6f}"


def record(name: str, out: Path, count: int, same_places: bool = False) -> list[str]:
    """Teach `count` demos of a task through the page into out/<task>; the page's last answer per demo."""
    t = task(name)
    scripted = [load_demo(p) for p in sorted((DEMOS_DIR / t.demos).glob(DEMO_GLOB))[:count]]
    with SimCell(CellConfig()) as cell:
        session = TeachSession(cell, t, out / t.name, np.array(cell.camera.config.T_base_cam))
        page = TeachPage(session, "127.0.0.1", free_port())
        driver = chromium()
        try:
            operator = Operator(page, driver)
            operator.open()
            return [operator.teach_one(d.seed, at=place_of(d.T_base_obj) if same_places else "")[-1] for d in scripted]
        finally:
            driver.quit()
            page.stop()
            session.close()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="directory whose <task>/ folders receive the demos")
    parser.add_argument("--demos", type=int, default=3, help="demos per task (default 3)")
    parser.add_argument("--tasks", default="mug,bowl,bottle")
    parser.add_argument("--same-places", action="store_true", help="put each object where its scripted demo stood")
    args = parser.parse_args()
    if (args.out).exists() and any(args.out.iterdir()):
        sys.exit(f"page_demos: --out {args.out} is not empty; choose a new directory")
    for name in args.tasks.split(","):
        for line in record(name, args.out, args.demos, args.same_places):
            print(f"{name}: {line}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
