"""`nift sim`: bring the simulated cell up, report what is there, and (with --gui) keep it open."""
from __future__ import annotations

import argparse
import json
import time

from app.console.options import add_config_argument, cell_config

NAME = "sim"
HELP = "bring the simulated cell up (UR5, gripper, Kinect v2, rack, shelf) and report its state"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--gui", action="store_true", help="open PyBullet's window and keep the cell running")
    p.add_argument("--seed", type=int, default=0, help="camera noise seed")
    p.add_argument("--json", action="store_true", help="print the state as JSON")
    add_config_argument(p)


def run(args: argparse.Namespace) -> int:
    from app.simcell.cell import SimCell

    with SimCell(cell_config(args, gui=args.gui)) as cell:
        t0 = time.perf_counter()
        frame = cell.camera.capture()
        state = {
            "arm_q": cell.arm.getActualQ().round(4).tolist(),
            "tcp_pose": cell.arm.getActualTCPPose().round(4).tolist(),
            "gripper_width": round(cell.gripper.width, 4),
            "camera": {"width": frame.intrinsics.width, "height": frame.intrinsics.height,
                       "frame_ms": round(1000 * (time.perf_counter() - t0), 1),
                       "valid_depth_fraction": round(float((frame.depth > 0).mean()), 3)},
            "fixtures": {name: cell.config.fixture_pose(name)[:3, 3].round(3).tolist() for name in cell.fixtures},
        }
        print(json.dumps(state, indent=2) if args.json else "\n".join(f"{k:<15} {v}" for k, v in state.items()))
        if args.gui:
            print("cell running in the PyBullet window; Ctrl-C to stop")
            try:
                while True:
                    cell.world.step(24)
                    time.sleep(0.1)
            except KeyboardInterrupt:
                pass
    return 0
