"""`nift run`: pick-and-place jobs in the simulated cell, end to end, on unseen objects."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from app.categories import POSES
from app.console.options import (add_config_argument, add_job_config_argument, add_second_look_argument, cell_config,
                                 job_config)

NAME = "run"
HELP = "run pick-and-place jobs in the sim cell: capture, imitate, plan, grasp, carry, place, verify"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from app.predict.methods import choices

    p.add_argument("--task", required=True, choices=["mug", "bowl", "bottle"], help="which task to do")
    p.add_argument("--pose", default="upright", choices=POSES,
                   help="how the object stands (arbitrary: held in mid-air until grasped; resting: dropped onto "
                        "the table and settled, as it fell)")
    p.add_argument("--seed", type=int, default=0, help="picks the unseen object, its scale and pose (job i: seed + i)")
    p.add_argument("--jobs", type=int, default=1, help="run a series of this many jobs")
    p.add_argument("--method", choices=choices(),
                   help="how grasp and place poses are found (default nift; oracle, alias teacher: the simulator's "
                        "ground truth)")
    p.add_argument("--object", metavar="NAME", help="an imported object (nift objects import) instead of unseen "
                   "procedural ones; each job puts it in a new pose")
    p.add_argument("--demos", type=Path, help="task directory (default demos/<task>)")
    p.add_argument("--record", type=Path, help="PNG strip of key frames (a series writes NAME-00.png, ...)")
    p.add_argument("--calibration", type=Path, default=Path("calibration.json"),
                   help="camera calibration file; if missing, the cell is calibrated first and it is written")
    p.add_argument("--gui", action="store_true", help="show the PyBullet window")
    p.add_argument("--devices", default="sim", choices=("sim", "net"),
                   help="sim: the simulated cell in this process; net: the devices `nift serve` offers, found with "
                        "zeroconf (give both the same --config)")
    p.add_argument("--keys", type=Path, help="folder of this client's CURVE keys and the server's public key "
                                             "(--devices net; default: nift serve's, ~/.config/nift/keys)")
    p.add_argument("--rerun", nargs="?", const="spawn", metavar="FILE.rrd",
                   help="record each job for the Rerun viewer: to FILE.rrd (a series: FILE-00.rrd, ...), or, without "
                        "a file, to a viewer it spawns (docs/recording.md)")
    p.add_argument("--json", action="store_true", help="print the result records as JSON")
    add_second_look_argument(p)
    add_config_argument(p)
    add_job_config_argument(p)


def run(args: argparse.Namespace) -> int:
    if args.jobs < 1:
        raise ValueError(f"--jobs must be at least 1, got {args.jobs}")
    if args.record is not None and args.record.suffix.lower() != ".png":
        raise ValueError(f"--record {args.record}: key frames are written as a PNG strip; give a .png path")
    if args.devices == "net" and (args.record is not None or args.gui):
        raise ValueError("--record and --gui need the simulated cell in this process (--devices sim)")
    if args.devices == "sim":
        cell_config(args)  # a bad --config fails here, in a second, not after the job path's imports
    job_log = _job_log(args)  # the recording's path checked before the job starts

    from app.tasks.task import task

    config = job_config(args)  # a bad --job-config fails here too
    t = task(args.task)
    source = imported(args.object, t, args.method) if args.object else None
    if source is not None and args.devices == "net":
        raise ValueError("--object needs the simulated cell in this process (--devices sim)")
    results = _run_net(args, t, config, job_log) if args.devices == "net" else _run_sim(args, t, config, job_log, source)
    return _report(results, args, t)


def imported(name: str, t, method: str):
    """The library object `name`, checked against the task and the method; a one-line error if unfit."""
    from app.objects.library import load_object
    from app.predict.methods import method as method_record

    source = load_object(name, category=t.category)
    if method_record(method).true_poses:
        raise ValueError(f"--method {method} needs a procedural object's landmarks and {name!r} is imported; "
                         f"use a learned method")
    return source


def _run_sim(args: argparse.Namespace, t, config, job_log, source=None) -> list:
    """The jobs in the simulated cell in this process (on the imported object `source`, if given)."""
    from tqdm import tqdm

    from app.motion.scene import PlanningScene
    from app.simcell.calibration import ensure_calibration
    from app.simcell.cell import SimCell
    from app.simcell.sim_job import JobSpec, run_series

    specs = [JobSpec(t, args.seed + i, args.pose, source) for i in range(args.jobs)]
    cell_cfg = cell_config(args, gui=args.gui)
    bar = tqdm(total=len(specs), unit="job", desc=f"nift run {t.name}", disable=len(specs) == 1 or args.json)
    done = []

    def report(result) -> None:
        done.append(result)
        bar.update(1)
        bar.set_postfix(success=f"{sum(r.success for r in done)}/{len(done)}")
        if not args.json and len(specs) > 1:
            bar.write(_line(result))

    with SimCell(cell_cfg) as cell:
        T_base_cam = ensure_calibration(cell, args.calibration)
        scene = PlanningScene(cell_cfg)
        try:
            return run_series(cell, scene, T_base_cam, specs, config, report, args.record, job_log=job_log)
        finally:
            scene.close()
            bar.close()


def _run_net(args: argparse.Namespace, t, config, job_log) -> list:
    """The jobs against `nift serve`'s devices (`app.jobs.remote`)."""
    from dataclasses import replace

    from app.config import load_toml
    from app.jobs.remote import NetCell, NetCellConfig, remote_calibration, run_remote_series
    from app.layout import CellLayout
    from hardware.net.client import NetDeviceConfig

    layout = load_toml(CellLayout, args.config, only_known=True) if args.config else CellLayout()
    device = NetDeviceConfig() if args.keys is None else NetDeviceConfig(keys=args.keys)
    net = NetCellConfig(device, device, device, replace(device, motion_timeout=600.0))
    with NetCell(net) as cell:
        T_base_cam = remote_calibration(cell, args.calibration)
        on_result = (lambda r: print(_line(r), flush=True)) if args.jobs > 1 and not args.json else (lambda r: None)
        return run_remote_series(cell, layout, t, [args.seed + i for i in range(args.jobs)], args.pose, T_base_cam,
                                 config, on_result, job_log=job_log)


def _job_log(args: argparse.Namespace):
    """i -> job i's log: a Rerun recording with --rerun (`app.recording`; its path checked now), else none."""
    if args.rerun is None:
        return lambda i: None
    from app.io_utils import numbered
    from app.recording.target import check_target, open_log

    path = check_target(args.rerun)
    return lambda i: open_log(numbered(path, i, args.jobs), f"seed-{args.seed + i}")


def _report(results: list, args: argparse.Namespace, t) -> int:
    if args.json:
        records = [r.record() for r in results]
        print(json.dumps(records[0] if len(records) == 1 else records, indent=2))
    elif len(results) == 1:
        _print_one(results[0])
    else:
        print(f"{sum(r.success for r in results)}/{len(results)} jobs succeeded ({t.name}, {args.pose}, {args.method})")
    return 0 if all(r.success for r in results) else 1


def _line(r) -> str:
    what = "ok" if r.success else f"FAILED at {r.failed_stage} ({r.failure_kind}): {r.reason}"
    which = r.info.get("object") or f"{r.task} {r.info['instance']}"
    return f"seed {r.info['seed']} ({which}, scale {r.info['scale']}): {what}"


def _print_one(r) -> None:
    print(_line(r))
    print("  stages (s): " + "  ".join(f"{k} {v:.2f}" for k, v in r.seconds.items()))
    if r.plan:
        print(f"  plan: {r.plan['planning_seconds']} s to plan, {r.plan['trajectory_seconds']} s of motion")
    if r.motion:
        print(f"  moved: {r.motion['motion_seconds']:.2f} s, {r.motion['joint_travel_rad']:.2f} rad of joint travel; "
              + "  ".join(f"{k} {v['motion_seconds']:.2f} s" for k, v in r.motion.get("by_stage", {}).items()))
    for name, pose in r.poses.items():
        print(f"  {name} TCP [x y z rx ry rz]: {pose}")
    if r.seen:
        print(f"  camera: {r.seen}")
    if r.look:
        print("  second look: " + ", ".join(f"{k} {v}" for k, v in r.look.items()))
    if len(r.attempts) > 1:
        print("  attempts: " + "; ".join(f"{a['attempt']}: {a['outcome']}" for a in r.attempts))
    print(f"  arm: {r.arm}")
    if "record" in r.info:
        print(f"  key frames: {r.info['record']}")
