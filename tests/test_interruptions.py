"""kill -9 at random moments (no clean-up runs): `nift make-data`, `nift teach` and `nift bench`.
Every later load works on a complete earlier state or says clearly what is wrong; no demo that
existed before is lost; no process the command started outlives it; the same command run again
finishes the work."""
import hashlib
import json
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import psutil
import pytest

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.slow


def nift_process(*args: str, cwd: Path) -> subprocess.Popen:
    script = Path(sys.executable).parent / "nift"
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "app.cli"]
    return subprocess.Popen([*cmd, *args], cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def kill_after(proc: subprocess.Popen, seconds: float) -> bool:
    """SIGKILL the process after `seconds` unless it ended first; whether it was killed. Every process
    it had started (Ray's servers, agents and workers included) is gone 30 s later (a wait that allows for
    two cores loaded by the rest of the suite)."""
    try:
        proc.wait(seconds)
        return False
    except subprocess.TimeoutExpired:
        try:
            descendants = psutil.Process(proc.pid).children(recursive=True)
        except psutil.Error:  # it ended just now
            descendants = []
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        alive = [p for p in psutil.wait_procs(descendants, timeout=30)[1] if running(p)]
        names = [name(p) for p in alive]
        for p in alive:
            p.kill()  # the test's own clean-up
        assert not alive, names
        return True


def name(p: psutil.Process) -> list[str] | str:
    """The process's command line's start, or what became of it (it may end while it is asked)."""
    try:
        return p.cmdline()[:3]
    except psutil.Error as exc:
        return f"pid {p.pid}: {type(exc).__name__}"


def running(p: psutil.Process) -> bool:
    """Alive and not a zombie (an orphan's zombie waits for an init that may never reap it: it is gone)."""
    try:
        return p.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def digest(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.glob("*.npz"))}


def test_make_data_killed_at_random_moments(tmp_path):
    from app.training.dataset import FieldData

    out = tmp_path / "data"
    rng = np.random.default_rng(0)
    for _ in range(4):
        kill_after(nift_process("make-data", "--quick", "--out", str(out), cwd=tmp_path), float(rng.uniform(0.5, 4.0)))
        if (out / "manifest.json").exists():
            json.loads((out / "manifest.json").read_text())  # never torn
            try:
                FieldData(out)
            except ValueError as exc:
                assert "incomplete" in str(exc) or "make-data" in str(exc), exc
    proc = nift_process("make-data", "--quick", "--out", str(out), cwd=tmp_path)  # the same command resumes
    assert proc.wait(300) == 0, proc.stderr.read()
    data = FieldData(out)
    assert data.manifest["complete"] and len(data.manifest["shards"]) == 3 and not list(out.glob("*.tmp*"))


def test_teach_killed_at_random_moments_loses_no_demo(tmp_path, true_calibration):
    from app.tasks.demo_library import task_demos, task_templates
    from app.tasks.staging import leftovers, recover
    from app.tasks.task import task

    calibration = true_calibration
    out = tmp_path / "mug"
    shutil.copytree(ROOT / "demos" / "mug", out)
    before = digest(out)
    rng = np.random.default_rng(1)
    for _ in range(3):
        killed = kill_after(nift_process("teach", "--task", "mug", "--out", str(out), "--replace", "--calibration",
                                         str(calibration), cwd=tmp_path), float(rng.uniform(1.0, 12.0)))
        assert killed  # a whole session takes minutes
        assert digest(out) == before  # the demos that were there are all there, unchanged
        assert len(task_demos(out)) == 10 and set(task_templates(task("mug"), out)) == {"grasp", "place"}
    assert leftovers(out)[0]  # a kill -9 runs no clean-up: its staging folder is still there ...
    recover(out)  # ... until the next session starts
    assert leftovers(out) == ([], []) and digest(out) == before


def test_bench_killed_at_random_moments_resumes(tmp_path):
    out = tmp_path / "bench"
    rng = np.random.default_rng(2)
    killed = []
    for _ in range(2):
        killed.append(kill_after(nift_process("bench", "--quick", "--tasks", "bowl,bottle", "--out", str(out),
                                              cwd=tmp_path), float(rng.uniform(8.0, 25.0))))  # on a local Ray
        if (out / "results.jsonl").exists():
            for line in (out / "results.jsonl").read_text().splitlines()[:-1]:  # all but a torn last line
                json.loads(line)
    proc = nift_process("bench", "--quick", "--tasks", "bowl,bottle", "--out", str(out), cwd=tmp_path)
    assert proc.wait(900) == 0, proc.stderr.read()
    rows = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    keys = [(r["trial"], r["method"]) for r in rows]
    assert any(killed) and len(keys) == len(set(keys))  # killed mid-run, then resumed, not repeated
