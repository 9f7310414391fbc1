import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from app.cli import COMMANDS, build_parser, main

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
DRAWS_NOTHING = {"devices"}  # verbs with nothing random, so no --seed


def nift(*args: str) -> subprocess.CompletedProcess:
    """Run the installed `nift` console script the way a user does (the module if not installed)."""
    script = Path(sys.executable).parent / "nift"
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "app.cli"]
    return subprocess.run([*cmd, *args], capture_output=True, text=True, timeout=300)


def test_help_lists_every_verb_and_each_verb_has_help():
    out = nift("--help")
    assert out.returncode == 0
    for command in COMMANDS:
        assert command.NAME in out.stdout
        sub = nift(command.NAME, "--help")
        assert sub.returncode == 0 and "--json" in sub.stdout
        assert ("--seed" in sub.stdout) == (command.NAME not in DRAWS_NOTHING), command.NAME


def test_objects_writes_a_sheet_and_json(tmp_path, capsys):
    out = tmp_path / "sheet.png"
    assert main(["objects", "--category", "bottle", "--count", "3", "--out", str(out), "--json",
                 "--export", str(tmp_path / "meshes")]) == 0
    report = json.loads(capsys.readouterr().out)
    assert [i["category"] for i in report["instances"]] == ["bottle"] * 3
    assert out.read_bytes()[:8] == PNG_MAGIC
    assert len(list((tmp_path / "meshes").glob("bottle-*.obj"))) == 3
    # same seed, same instances; another seed, others
    assert main(["objects", "--category", "bottle", "--count", "3", "--out", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["instances"] == report["instances"]
    assert main(["objects", "--category", "bottle", "--count", "3", "--out", str(out), "--json", "--seed", "9"]) == 0
    assert json.loads(capsys.readouterr().out)["instances"] != report["instances"]


def test_bad_input_gives_one_line_error():
    out = nift("objects", "--count", "0", "--out", "/tmp/never.png")
    assert out.returncode == 2
    assert out.stderr.strip().count("\n") == 0 and "--count must be between" in out.stderr
    with pytest.raises(SystemExit):
        build_parser().parse_args(["objects", "--category", "teapot"])
    for args, named in ((("run", "--task", "cup"), "invalid choice: 'cup'"), (("run",), "--task"),
                        (("bogus",), "invalid choice: 'bogus'")):
        out = nift(*args)  # argparse's own errors: one line, no usage text before it
        assert out.returncode == 2 and out.stderr.strip().count("\n") == 0 and named in out.stderr, out.stderr
        assert "usage:" not in out.stderr


def test_bench_geometry_quick_reports_every_figure():
    out = nift("bench-geometry", "--quick", "--json")
    assert out.returncode == 0, out.stderr
    figures = json.loads(out.stdout)
    for key in ("raw_mrays_per_s", "scf_points_per_s", "scf_fraction_of_raw", "ibs_seconds"):  # timings
        assert figures[key] > 0, key
    assert figures["directions"] == 974
    # accuracy, deterministic: 974 Lebedev directions agree with 5,810 to a few per cent, SCF is
    # rotation invariant to the same, a dense surface cloud's c_0 matches the mesh's, IBS points are equidistant
    assert figures["scf_direction_error_p95"] < 0.05 and figures["scf_rotation_error_p95"] < 0.06
    assert figures["scf_cloud_r2_per_band"][0] > 0.95 and figures["scf_cloud_r2_mean"] > 0.7
    assert figures["scf_single_view_r2_mean"] < figures["scf_cloud_r2_mean"]  # one view sees half the object
    assert figures["ibs_gap_max_mm"] < figures["ibs_sample_spacing_mm"]


@pytest.mark.slow
def test_sim_and_capture_write_what_they_say(tmp_path):
    out = nift("sim", "--json")
    assert out.returncode == 0, out.stderr
    state = json.loads(out.stdout[out.stdout.index("{"):])
    assert state["gripper_width"] > 0.08 and set(state["fixtures"]) == {"rack", "shelf"}

    cloud, image = tmp_path / "cloud.ply", tmp_path / "rgb.png"
    out = nift("capture", "--category", "mug", "--seed", "1", "--out", str(cloud), "--image", str(image), "--json",
               "--calibration", str(tmp_path / "calibration.json"))  # missing: capture calibrates first
    assert (tmp_path / "calibration.json").exists()
    assert out.returncode == 0, out.stderr
    report = json.loads(out.stdout[out.stdout.index("{"):])
    import open3d as o3d

    points = np.asarray(o3d.io.read_point_cloud(str(cloud)).points)
    assert points.shape == (report["points"], 3) == (1024, 3)
    # the cloud is where the object was spawned, within the object's size
    assert np.linalg.norm(points.mean(axis=0)[:2] - np.array(report["object_position"][:2])) < 0.08
    assert image.read_bytes()[:8] == PNG_MAGIC
    bad = nift("capture", "--out", str(tmp_path / "cloud.txt"), "--calibration", str(tmp_path / "calibration.json"))
    assert bad.returncode == 2 and "cloud.txt must end in .ply" in bad.stderr


def test_bench_cell_quick_reports_figures():
    out = nift("bench-cell", "--quick", "--json")
    assert out.returncode == 0, out.stderr
    figures = json.loads(out.stdout[out.stdout.index("{"):])
    assert figures["real_time_factor_moveJ"] > 1.0  # faster than real time in DIRECT mode
    assert 0 < figures["camera_frame_ms"] < 5000 and 0 < figures["perception_ms"] < 5000
    # eye-to-hand calibration against the simulator's true camera pose: about a millimetre off
    assert figures["calibration_views"] == 12 and figures["calibration_reprojection_px"] < 1.0
    assert figures["calibration_error_mm"] < 3.0 and figures["calibration_error_deg"] < 0.5


@pytest.mark.slow
def test_run_prints_clean_json_and_writes_key_frames(tmp_path):
    strip = tmp_path / "job.png"
    out = nift("run", "--task", "bowl", "--method", "teacher", "--seed", "1", "--json", "--record", str(strip),
               "--calibration", str(tmp_path / "calibration.json"))
    record = json.loads(out.stdout)  # nothing but the JSON on stdout (no pybullet banner)
    assert out.returncode == 0 and record["success"] is True, out.stderr[-500:]
    assert record["failed_stage"] is None and record["arm"] == "home"
    assert strip.read_bytes()[:8] == PNG_MAGIC
    assert (tmp_path / "calibration.json").exists()  # a clean cell calibrates itself first


def test_run_refuses_bad_options_in_one_line(tmp_path):
    out = nift("run", "--task", "mug", "--record", str(tmp_path / "job.mp4"))
    assert out.returncode == 2 and "PNG" in out.stderr and len(out.stderr.strip().splitlines()) == 1
    out = nift("run", "--task", "mug", "--jobs", "0")
    assert out.returncode == 2 and "--jobs" in out.stderr
    out = nift("bench", "--tasks", "cup", "--out", str(tmp_path / "b"))
    assert out.returncode == 2 and "unknown task 'cup'" in out.stderr


def test_imitation_flags_out_of_range_end_in_one_line_before_any_work(tmp_path):
    from app.tasks.demo_library import DEMOS_DIR, task_demos

    cloud = tmp_path / "cloud.npy"
    np.save(cloud, task_demos(DEMOS_DIR / "mug")[0].cloud)
    out = nift("imitate", "--task", "mug", "--cloud", str(cloud), "--inits", "1000000")
    assert out.returncode == 2 and out.stderr.strip().count("\n") == 0
    assert "inits must be in [1, 1000], got 1000000" in out.stderr


@pytest.mark.parametrize("change, message", [
    (lambda c: c * 1000.0, "if they are millimetres: give the cloud in metres"),
    (lambda c: c + [20.0, 0.0, 0.0], "m from the robot's base"),
    (lambda c: (c - c.mean(axis=0)) * 0.05 + c.mean(axis=0), "mm; an object cloud spans"),
    (lambda c: c * 10.0, "m; an object cloud spans"),
    (lambda c: np.repeat(c[:5], 50, axis=0), "5 distinct points"),
])
def test_imitate_refuses_a_cloud_no_object_in_the_cell_could_be_in_one_line(tmp_path, change, message):
    """A demo's mug cloud in millimetres, 20 m away, shrunk to 5 mm, ten times too big or of 5 points."""
    from app.tasks.demo_library import DEMOS_DIR, task_demos

    cloud = tmp_path / "cloud.npy"
    np.save(cloud, change(task_demos(DEMOS_DIR / "mug")[0].cloud))
    out = nift("imitate", "--task", "mug", "--cloud", str(cloud))
    assert out.returncode == 2 and out.stderr.strip().count("\n") == 0, out.stderr
    assert message in out.stderr and str(cloud) in out.stderr


def _calibration_dir(tmp_path):
    (tmp_path / "calib").mkdir()
    return ["run", "--task", "bowl", "--method", "teacher", "--calibration", str(tmp_path / "calib")], "calib"


def _manifest_list(tmp_path):
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "manifest.json").write_text("[1, 2]")
    return ["train", "--target", "scf", "--data", str(tmp_path / "data"), "--out", str(tmp_path / "runs")], "manifest.json"


def _bench_out_file(tmp_path):
    (tmp_path / "results.txt").write_text("mine")
    return ["bench", "--quick", "--out", str(tmp_path / "results.txt")], "results.txt"


@pytest.mark.parametrize("case", [_calibration_dir, _manifest_list, _bench_out_file])
def test_bad_paths_end_in_one_line_naming_them_and_leave_nothing_behind(tmp_path, case):
    args, name = case(tmp_path)
    before = sorted(p.name for p in tmp_path.rglob("*"))
    out = nift(*args)
    assert out.returncode == 2 and out.stderr.strip().count("\n") == 0, out.stderr
    assert name in out.stderr and "Traceback" not in out.stderr
    assert sorted(p.name for p in tmp_path.rglob("*")) == before  # no run directory, no temp file
    if name == "results.txt":
        assert (tmp_path / "results.txt").read_text() == "mine"  # the user's file is untouched


def test_an_unexpected_error_is_one_line_naming_a_log_that_holds_the_traceback(tmp_path, monkeypatch, capsys):
    from app.commands import objects

    def broken(args):
        raise RuntimeError("a bug of ours")

    monkeypatch.setattr(objects, "run", broken)
    monkeypatch.setenv("NIFT_LOG_DIR", str(tmp_path))
    assert main(["objects", "--category", "mug", "--count", "1", "--out", str(tmp_path / "x.png")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "internal error: RuntimeError: a bug of ours" in err[0]
    log = next(tmp_path.glob("nift-objects-*.log"))
    assert str(log) in err[0] and "Traceback" in log.read_text() and "a bug of ours" in log.read_text()


@pytest.mark.parametrize("text, said", [
    ("garbage\n", "unable to parse header"),
    ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n", "Error reading 'x'"),
])
def test_a_broken_ply_is_one_line_and_open3d_prints_nothing_of_its_own(tmp_path, text, said):
    cloud = tmp_path / "bad.ply"
    cloud.write_text(text)
    out = nift("imitate", "--task", "mug", "--cloud", str(cloud))
    assert out.returncode == 2 and out.stdout == "" and out.stderr.strip().count("\n") == 0, (out.stdout, out.stderr)
    assert "not a readable PLY cloud" in out.stderr and said in out.stderr


def test_a_bench_that_fails_to_start_leaves_no_folder_and_bad_weights_fail_first(tmp_path, monkeypatch, capsys):
    import app.bench.runner as runner

    def failing(config, out, *args, **kwargs):
        out.mkdir(parents=True)
        (out / "run.json").write_text("{}")  # half prepared
        raise ValueError("demos could not be prepared")

    monkeypatch.setattr(runner, "run", failing)
    out = tmp_path / "bench"
    assert main(["bench", "--quick", "--out", str(out)]) == 2
    assert not out.exists() and "demos could not be prepared" in capsys.readouterr().err
    (tmp_path / "empty.pt").write_bytes(b"")
    assert main(["bench", "--quick", "--out", str(out), "--nif", str(tmp_path / "empty.pt")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("nift bench: error:") and "empty.pt" in err and not out.exists()  # no progress bar first
