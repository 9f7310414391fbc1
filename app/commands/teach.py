"""`nift teach`: record verified demos of a task in the sim cell and rebuild its templates."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from app.console.options import add_config_argument, cell_config

NAME = "teach"
HELP = "record demos of a task (scripted teacher or your poses), verify them, rebuild the task's NIT"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--task", required=True, choices=["mug", "bowl", "bottle"], help="which task to teach")
    p.add_argument("--demos", type=int, default=10, help="verified demos to record (default 10)")
    p.add_argument("--out", type=Path, help="task directory (default demos/<task>)")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--replace", action="store_true", help="the new demos take the place of those in --out")
    mode.add_argument("--add", action="store_true", help="the new demos join those in --out")
    p.add_argument("--poses", type=Path, help="JSON with your poses for ONE demo (added to the others unless "
                   "--replace): {\"instance\": seed, "
                   "\"T_obj_tcp\": 4x4, \"T_fixture_obj\": 4x4}; default: the scripted teacher")
    p.add_argument("--rebuild", action="store_true", help="only rebuild the templates from the demos there")
    p.add_argument("--calibration", type=Path, default=Path("calibration.json"),
                   help="camera calibration file; if missing, the cell is calibrated first and it is written")
    p.add_argument("--seed", type=int, default=0, help="which train-split instances are used, and their poses")
    p.add_argument("--json", action="store_true", help="print what was recorded as JSON")
    web = p.add_argument_group("the teach page (--web)")
    web.add_argument("--web", action="store_true", help="teach by hand in the browser: freedrive, grasp, place, save")
    web.add_argument("--host", default="127.0.0.1", help="address the page is served on (default 127.0.0.1: this "
                     "machine only; the page answers only the token in the URL it prints)")
    web.add_argument("--port", type=int, default=8080, help="its port (default 8080)")
    web.add_argument("--rerun", action="store_true", help="record the session for the Rerun viewer beside the demo "
                                                           "folder, OUT-session-TIME.rrd (docs/recording.md)")
    web.add_argument("--object", metavar="NAME", help="teach on an imported object (nift objects import) instead of "
                     "procedural ones")
    add_config_argument(p)


def read_poses(path: Path):
    """An operator's poses file -> (instance seed, TaughtPoses)."""
    import numpy as np

    from app.simcell.scripted_demos import TaughtPoses

    if not path.is_file():
        raise FileNotFoundError(f"no poses file at {path}")
    try:
        data = json.loads(path.read_text())
        return int(data["instance"]), TaughtPoses(np.array(data["T_obj_tcp"], float).reshape(4, 4),
                                                  np.array(data["T_fixture_obj"], float).reshape(4, 4))
    except (json.JSONDecodeError, KeyError, ValueError, TypeError) as exc:
        raise ValueError(f"{path}: expected JSON with instance, T_obj_tcp and T_fixture_obj ({exc})") from None


def _interrupt(flag) -> None:
    """Ctrl-C: remember it, then raise. A library that swallows the KeyboardInterrupt while the page
    starts (trimesh catches BaseException while loading the URDF's meshes) cannot hide it."""
    flag.set()
    raise KeyboardInterrupt


def web(args: argparse.Namespace, t, out: Path) -> int:
    """`nift teach --web`: the teach page on the live simulated cell until Ctrl-C."""
    import signal
    import threading

    from app.io_utils import writable_directory
    from app.objects.library import load_object

    if not args.web:
        raise ValueError("--object teaches by hand: add --web (the scripted teacher needs procedural objects)")
    if args.poses or args.rebuild or args.replace:
        raise ValueError("--web records demos one at a time on the page; leave out --poses, --rebuild and --replace")
    if not 1 <= args.port <= 65535:
        raise ValueError(f"--port must be 1-65535, got {args.port}")
    writable_directory(out, "--out")
    source = load_object(args.object, category=t.category) if args.object else None
    if args.rerun:
        from app.recording.target import check_target

        check_target(str(out.parent), "--rerun", folder=True)  # where the session's recording goes (beside `out`)

    from app.simcell.calibration import ensure_calibration
    from app.simcell.cell import SimCell
    from app.teach.page import TeachPage
    from app.teach.session import TeachSession

    interrupted = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: _interrupt(interrupted))
    with SimCell(cell_config(args)) as cell:
        T_base_cam = ensure_calibration(cell, args.calibration)
        session = TeachSession(cell, t, out, T_base_cam, source, args.seed)
        recording = _recording(session, out) if args.rerun else None
        page = TeachPage(session, args.host, args.port)
        where = "" if args.host in ("127.0.0.1", "localhost", "::1") else " (reachable from the network; unencrypted: anyone who sees the URL holds the token)"
        kept = f"; the session is recorded to {recording.path}" if recording else ""
        print(f"teach page for {t.name} on {page.url}{where}; demos go to {out}{kept}; Ctrl-C stops", flush=True)
        try:
            while not interrupted.wait(1.0):
                pass
        except KeyboardInterrupt:
            print("teach page stopped", flush=True)
        finally:
            page.stop()
            session.close()
            if recording:
                recording.close()
    return 0


def _recording(session, out: Path):
    """The session's Rerun recording, told of every step (`app.recording.session_log`)."""
    from app.recording.session_log import SessionRecording, session_path

    recording = SessionRecording(session_path(out))
    session.observers.append(recording.step)
    return recording


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from app.tasks.demo import DEMOS_DIR
    from app.tasks.staging import demo_count, staged, teach_mode
    from app.tasks.task import task

    t = task(args.task)
    out = args.out or DEMOS_DIR / t.name
    if args.web or args.object:
        return web(args, t, out)
    if args.rerun:
        raise ValueError("--rerun records a session on the teach page: add --web")
    if not args.rebuild:
        # one demo from a poses file joins the others unless --replace says otherwise
        mode = teach_mode(out, args.replace, args.add or (args.poses is not None and not args.replace))
        poses = read_poses(args.poses) if args.poses else None

    from app.simcell.cell import SimCell  # bad input has failed by now, before the simulator's imports
    from app.simcell.scripted_demos import record_demo, record_task
    from app.tasks.demo_library import task_demos, task_templates

    log = (lambda line: print(line, file=sys.stderr)) if args.json else print
    recorded = []
    if args.rebuild:
        templates = task_templates(t, out, rebuild=True)
    else:
        with SimCell(cell_config(args)) as cell, staged(out, mode) as stage:
            from app.simcell.calibration import ensure_calibration

            T_base_cam = ensure_calibration(cell, args.calibration)
            first = demo_count(stage)
            if poses:
                from app.tasks.demo import save_demo

                instance, taught = poses
                demo, why = record_demo(cell, t, instance, T_base_cam, np.random.default_rng(args.seed), taught,
                                        name=f"demo-{first:02d}")
                if demo is None:
                    raise ValueError(f"the demo was not kept: {why}")
                recorded = [save_demo(demo, stage / f"{demo.name}.npz")]
            else:
                recorded = record_task(cell, t, args.demos, stage, T_base_cam, args.seed, report=log, first=first)
            templates = task_templates(t, stage, rebuild=True)  # in the staging folder: swapped in with the demos
        recorded = [out / p.name for p in recorded]
    report = {"task": t.name, "directory": str(out), "recorded": [str(p) for p in recorded],
              "demos": len(task_demos(out)),
              "templates": {s: {"points": len(tp.points), "feature_dim": int(tp.features.shape[1])}
                            for s, tp in templates.items()}}
    sizes = ", ".join(f"{stage} {len(tp.points)} points" for stage, tp in templates.items())
    print(json.dumps(report, indent=2) if args.json else
          f"{t.name}: {len(recorded)} demos recorded, {report['demos']} in {out}; templates rebuilt ({sizes})")
    return 0
