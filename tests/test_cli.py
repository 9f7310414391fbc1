import json
import subprocess
import sys
from pathlib import Path

import pytest

from app.cli import COMMANDS, build_parser, main

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


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
        assert sub.returncode == 0 and "--seed" in sub.stdout and "--json" in sub.stdout


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


def test_bench_geometry_quick_reports_every_figure():
    out = nift("bench-geometry", "--quick", "--json")
    assert out.returncode == 0, out.stderr
    figures = json.loads(out.stdout)
    for key in ("raw_mrays_per_s", "scf_points_per_s", "scf_fraction_of_raw", "ibs_seconds",
                "scf_direction_error_p95", "scf_rotation_error_p95", "scf_cloud_r2_mean", "ibs_gap_max_mm"):
        assert figures[key] > 0, key
    assert figures["directions"] == 974
    assert figures["ibs_gap_max_mm"] < figures["ibs_sample_spacing_mm"]
