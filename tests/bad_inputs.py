"""The corpus of bad inputs for `tests/test_bad_inputs.py`: (arguments, text the one error line
must contain - the input it names). Files named here are made by `make_inputs`."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import trimesh

from app.objects import generate

CORPUS: list[tuple[tuple[str, ...], str]] = [
    # run
    (("run", "--task", "mug", "--jobs", "0"), "--jobs"),
    (("run", "--task", "mug", "--jobs", "-3"), "--jobs"),
    (("run", "--task", "teapot"), "--task"),
    (("run", "--task", "mug", "--seed", "abc"), "--seed"),
    (("run", "--task", "mug", "--pose", "sideways"), "--pose"),
    (("run", "--task", "mug", "--record", "job.txt"), "job.txt"),
    (("run", "--task", "mug", "--config", "missing.toml"), "missing.toml"),
    (("run", "--task", "mug", "--config", "bad.toml"), "bad.toml"),
    (("run", "--task", "mug", "--config", "unknown.toml"), "colour"),
    (("run", "--task", "mug", "--config", "string.toml"), "time_step"),
    (("run", "--task", "mug", "--config", "negative.toml"), "time_step"),
    (("run", "--task", "mug", "--config", "noise.toml"), "camera_noise"),
    (("run", "--task", "mug", "--config", "force.toml"), "contact_force_limit"),
    (("run", "--task", "mug", "--config", "far-rack.toml"), "rack_xy_yaw's x, y [1e+30, 0.4] is 1e+30 m from the robot base"),
    (("sim", "--config", "far-eye.toml"), "camera_eye [0.5, 1e+30, 0.5] is 1e+30 m"),
    (("bench-jobs", "--config", "blind.toml"), "at least 0.1 m apart"),
    (("run", "--task", "mug", "--method", "magic"), "--method"),
    (("run", "--task", "mug", "--devices", "net", "--record", "job.png"), "--record"),
    (("run", "--task", "mug", "--devices", "wifi"), "--devices"),
    # imitate
    (("imitate", "--task", "mug", "--cloud", "missing.ply"), "missing.ply"),
    (("imitate", "--task", "mug", "--cloud", "empty.ply"), "empty.ply"),
    (("imitate", "--task", "mug", "--cloud", "garbage.ply"), "garbage.ply"),
    (("imitate", "--task", "mug", "--cloud", "mm.ply"), "millimetres"),
    (("imitate", "--task", "mug", "--cloud", "far.ply"), "far.ply"),
    (("imitate", "--task", "mug", "--cloud", "three.ply"), "three.ply"),
    (("imitate", "--task", "mug", "--cloud", "nan.ply"), "nan.ply"),
    (("imitate", "--task", "mug", "--cloud", "adir"), "adir"),
    (("imitate", "--task", "mug", "--cloud", "good.ply", "--inits", "0"), "inits"),
    (("imitate", "--task", "mug", "--cloud", "good.ply", "--inits", "1000000"), "inits"),
    (("imitate", "--task", "mug", "--cloud", "good.ply", "--iterations", "0"), "iterations"),
    (("imitate", "--task", "mug", "--cloud", "good.ply", "--patience", "-1"), "patience"),
    (("imitate", "--task", "mug", "--cloud", "good.ply", "--place-contact-scale", "-1"), "place_contact_scale"),
    (("imitate", "--task", "mug", "--cloud", "good.ply", "--method", "magic"), "--method"),
    (("imitate", "--task", "mug", "--cloud", "good.ply", "--demos", "missing-demos"), "missing-demos"),
    (("imitate", "--task", "mug", "--cloud", "good.ply", "--demos", "emptydata"), "emptydata"),
    # capture, calibrate, objects, sim
    (("capture", "--category", "teapot", "--out", "c.ply"), "--category"),
    (("capture", "--category", "mug", "--out", "afile/c.ply"), "afile"),
    (("capture", "--category", "mug", "--out", "c.ply", "--calibration", "garbage.json"), "garbage.json"),
    (("capture", "--category", "mug", "--out", "c.ply", "--calibration", "list.json"), "list.json"),
    (("capture", "--category", "mug", "--out", "c.ply", "--calibration", "adir"), "adir"),
    (("calibrate", "--out", "cal.json", "--views", "0"), "--views"),
    (("calibrate", "--out", "cal.json", "--config", "bad.toml"), "bad.toml"),
    (("calibrate", "--out", "adir"), "adir"),
    (("objects", "--category", "mug", "--count", "0"), "--count"),
    (("objects", "--category", "teapot"), "--category"),
    (("objects", "--category", "mug", "--out", "sheet.txt"), "sheet.txt"),
    (("sim", "--config", "unknown.toml"), "colour"),
    (("objects", "import", "notamesh.obj", "--category", "mug"), "notamesh.obj"),
    (("objects", "import", "missing.obj", "--category", "mug"), "missing.obj"),
    (("objects", "import", "mug-mm.stl", "--category", "mug", "--units", "m"), "--units"),
    (("objects", "import", "sheet.stl", "--category", "mug"), "sheet.stl"),
    (("objects", "import", "fin.stl", "--category", "mug"), "fin.stl"),
    (("objects", "import", "mug-mm.stl", "--category", "mug", "--name", "My Mug"), "My Mug"),
    (("objects", "import", "mug-mm.stl", "--category", "mug", "--name", "mug2\n"), "mug2"),
    (("objects", "import", "mug-mm.stl", "--category", "teapot"), "--category"),
    (("objects", "import", "mug-mm.stl", "--category", "mug", "--collision-faces", "5"), "--collision-faces"),
    (("objects", "import-set", "nosuch.toml"), "nosuch.toml"),
    (("objects", "import-set", "unknown.toml"), "unknown.toml"),
    (("run", "--task", "mug", "--object", "nosuch"), "nosuch"),
    (("bench-jobs", "--objects", "nosuch", "--jobs", "1"), "nosuch"),
    (("bench", "--tasks", "mug", "--objects", "nosuch", "--out", "b"), "nosuch"),
    (("bench", "--demo-dir", "missing-demos", "--out", "b"), "missing-demos"),
    # make-data, train
    (("make-data", "--out", "data", "--instances", "0"), "--instances"),
    (("make-data", "--out", "afile"), "afile"),
    (("make-data", "--out", "data", "--categories", "teapot"), "teapot"),
    (("make-data", "--out", "data", "--points", "-5"), "--points"),
    (("train", "--target", "scf", "--data", "missing-data", "--out", "run1"), "missing-data"),
    (("train", "--target", "scf", "--data", "emptydata", "--out", "run1"), "emptydata"),
    (("train", "--target", "scf", "--data", "emptydata", "--out", "run1", "--epochs", "0"), "--epochs"),
    (("train", "--target", "colour", "--data", "emptydata", "--out", "run1"), "--target"),
    (("train", "--target", "scf", "--data", "emptydata", "--out", "run1", "--lr", "-1"), "--lr"),
    (("train", "--target", "scf", "--data", "emptydata", "--out", "afile"), "afile"),
    (("train", "--target", "scf", "--data", "emptydata", "--out", "run1", "--minutes", "-2"), "--minutes"),
    (("train", "--target", "scf", "--data", "emptydata", "--out", "run1", "--batch-size", "0"), "--batch-size"),
    # teach
    (("teach", "--task", "teapot"), "--task"),
    (("teach", "--task", "mug", "--replace", "--add"), "--add"),
    (("teach", "--task", "mug", "--out", "afile"), "afile"),
    (("teach", "--task", "mug", "--out", "new", "--poses", "poses.json"), "poses.json"),
    (("teach", "--task", "mug", "--out", "new", "--poses", "missing.json"), "missing.json"),
    (("teach", "--task", "mug", "--web", "--port", "70000"), "--port"),
    (("teach", "--task", "mug", "--web", "--object", "nosuch"), "nosuch"),
    (("teach", "--task", "mug", "--object", "nosuch"), "--web"),
    (("teach", "--task", "mug", "--web", "--poses", "poses.json"), "--poses"),
    # bench, bench-jobs, the other benches
    (("bench", "--trials", "0"), "--trials"),
    (("bench", "--out", "afile"), "afile"),
    (("bench", "--methods", "magic", "--out", "b"), "magic"),
    (("bench", "--tasks", "teapot", "--out", "b"), "teapot"),
    (("bench", "--poses", "sideways", "--out", "b"), "sideways"),
    (("bench", "--fields", "missing-weights", "--out", "b"), "missing-weights"),
    (("bench-jobs", "--jobs", "0"), "--jobs"),
    (("bench-jobs", "--tasks", "teapot"), "teapot"),
    (("bench-jobs", "--config", "negative.toml"), "time_step"),
    (("bench-imitation", "--inits", "0"), "inits"),
    (("bench-imitation", "--busy", "-1"), "--busy"),
    (("bench", "--workers", "0", "--out", "b"), "--workers"),
    (("make-data", "--workers", "-3", "--out", "d"), "--workers"),
    (("make-data", "--workers", "0", "--out", "d"), "--workers"),
    (("bench-imitation", "--workers", "0"), "--workers"),
    (("bench", "--address", "127.0.0.1:9", "--out", "b"), "127.0.0.1:9"),
    (("make-data", "--address", "no-port-here", "--out", "d"), "no-port-here"),
    # the network
    (("serve", "--add-client", "afile", "--keys", "keys"), "afile"),
    (("run", "--task", "mug", "--rerun", "nodir/job.rrd"), "nodir"),
    (("run", "--task", "mug", "--rerun", "job.txt"), ".rrd"),
    (("run", "--task", "mug", "--rerun", "/sys/job.rrd"), "/sys"),
    (("teach", "--task", "mug", "--rerun"), "--web"),
    (("bench-jobs", "--quick", "--rerun", "no-such-dir"), "no-such-dir"),
    (("serve", "--bind", "not-an-address"), "--bind"),
    (("serve", "--bind", "::1"), "--bind"),
    (("serve", "--devices", "toaster"), "--devices"),
    (("serve", "--watchdog", "0", "--keys", "keys"), "watchdog"),
    (("serve", "--port", "70000", "--keys", "keys"), "port"),
    (("serve", "--add-client", "no-such.key", "--keys", "keys"), "no-such.key"),
    (("devices", "--timeout", "0"), "--timeout"),
    (("bench-net", "--reads", "0"), "--reads"),
    (("run", "--task", "mug", "--devices", "net", "--keys", "missing-keys"), "missing-keys"),
]


def _ply(path: Path, points: np.ndarray) -> None:
    lines = [f"{x} {y} {z}" for x, y, z in points]
    path.write_text("ply\nformat ascii 1.0\n"
                    f"element vertex {len(points)}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
                    + "\n".join(lines) + "\n")


def make_inputs(root: Path) -> None:
    """The bad (and the one good) input files the corpus names, in `root`."""
    pts = np.random.default_rng(0).normal(size=(500, 3)) * 0.03 + [0.5, 0.0, 0.05]
    _ply(root / "good.ply", pts)
    _ply(root / "mm.ply", pts * 1000)
    _ply(root / "far.ply", pts + [20.0, 0.0, 0.0])
    _ply(root / "three.ply", pts[:3])
    _ply(root / "nan.ply", np.vstack([pts, [[np.nan] * 3]]))
    (root / "garbage.ply").write_bytes(np.random.default_rng(1).bytes(300))
    (root / "empty.ply").write_text("")
    files = {"bad.toml": "this is = = not toml", "unknown.toml": "colour = 3\n",
             "string.toml": "[world]\ntime_step = 'fast'\n", "negative.toml": "[world]\ntime_step = -0.01\n",
             "noise.toml": "camera_noise = 'yes'\n", "force.toml": "[arm]\ncontact_force_limit = -5.0\n",
             "far-rack.toml": "rack_xy_yaw = [1e30, 0.4, 3.14]\n", "far-eye.toml": "camera_eye = [0.5, 1e30, 0.5]\n",
             "blind.toml": "camera_eye = [0.5, 0.0, 0.05]\n",
             "garbage.json": "{not json", "list.json": "[1, 2, 3]", "poses.json": '{"grasp": 3}', "afile": "x"}
    for name, text in files.items():
        (root / name).write_text(text)
    (root / "notamesh.obj").write_text("v 0 0 zero\nthis is not a mesh\n")
    sheet = trimesh.Trimesh([[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0, 0.1, 0]], [[0, 1, 2], [0, 2, 3]])
    sheet.export(root / "sheet.stl")
    fin = trimesh.Trimesh([[0, 0, 0], [0, 0, 0.1], [0.1, 0, 0.05], [0, 0.1, 0.05], [-0.1, -0.05, 0.05]],
                          [[0, 1, 2], [0, 1, 3], [0, 1, 4]], process=False)  # three faces on one edge: non-manifold
    fin.export(root / "fin.stl")
    mug = generate("mug", 1)
    mug.apply_scale(1000.0)  # millimetres: as metres, 100 m across
    mug.export(root / "mug-mm.stl")
    for name in ("adir", "emptydata"):
        (root / name).mkdir()
    os.chmod(root / "afile", 0o644)
