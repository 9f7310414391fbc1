"""A corpus of bad inputs across the verbs, each run as its own `nift` process (forked from one that
imported the CLI once: tests/cli_forkserver.py): exit code 2, exactly one line on stderr that names
the input, and the working directory left exactly as it was (no file written, none removed, no temp
file, no empty folder). One case also runs as the installed `nift` script, the way a user starts it."""
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from bad_inputs import CORPUS, make_inputs


def snapshot(root: Path) -> dict[str, tuple[int, int]]:
    return {str(p.relative_to(root)): (p.stat().st_size if p.is_file() else -1, p.stat().st_mtime_ns)
            for p in sorted(root.rglob("*"))}


def run_case(args: tuple[str, ...], cwd: Path, env: dict) -> subprocess.CompletedProcess:
    script = Path(sys.executable).parent / "nift"
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "app.cli"]
    return subprocess.run([*cmd, *args], cwd=cwd, capture_output=True, text=True, timeout=300, env=env)


def run_forked(cases: list, root: Path, env: dict) -> list[subprocess.CompletedProcess]:
    """Each case (args, named, cwd, snapshot) run by the fork server; its exit code, stdout and stderr."""
    out = root / "outputs"
    out.mkdir()
    jobs = [{"args": list(args), "cwd": str(cwd), "stdout": str(out / f"{i}.out"), "stderr": str(out / f"{i}.err")}
            for i, (args, _, cwd, _) in enumerate(cases)]
    (root / "cases.json").write_text(json.dumps(jobs))
    server = Path(__file__).with_name("cli_forkserver.py")
    proc = subprocess.Popen([sys.executable, str(server), str(root / "cases.json"), str(root / "codes.json")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, start_new_session=True)
    try:
        _, stderr = proc.communicate(timeout=900)
    except subprocess.TimeoutExpired:  # a case that does not end (a server that serves): none of it is left running
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        raise
    assert proc.returncode == 0, stderr[-2000:]
    codes = json.loads((root / "codes.json").read_text())
    return [subprocess.CompletedProcess(j["args"], code, Path(j["stdout"]).read_text(), Path(j["stderr"]).read_text())
            for j, code in zip(jobs, codes)]


def test_a_bad_input_to_the_installed_script_is_one_line_and_exit_2(tmp_path):
    r = run_case(("run", "--task", "teapot"), tmp_path, {**os.environ, "NIFT_LOG_DIR": str(tmp_path / "logs")})
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "--task" in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_the_corpus_is_large_enough_and_covers_the_verbs():
    assert len(CORPUS) >= 60
    verbs = {args[0] for args, _ in CORPUS}
    assert {"run", "imitate", "capture", "calibrate", "make-data", "train", "teach", "bench", "bench-jobs",
            "objects", "serve"} <= verbs


@pytest.mark.slow
def test_every_bad_input_ends_in_one_line_naming_it_and_leaves_the_directory_as_it_was(tmp_path):
    env = {**os.environ, "NIFT_LOG_DIR": str(tmp_path / "logs"), "HOME": str(tmp_path / "home")}
    cases = []
    for i, (args, named) in enumerate(CORPUS):
        cwd = tmp_path / f"case-{i:02d}"
        cwd.mkdir()
        make_inputs(cwd)
        cases.append((args, named, cwd, snapshot(cwd)))
    results = run_forked(cases, tmp_path, env)
    failures = []
    for (args, named, cwd, before), r in zip(cases, results):
        lines = r.stderr.strip().splitlines()
        problems = []
        if r.returncode != 2:
            problems.append(f"exit {r.returncode}")
        if len(lines) != 1:
            problems.append(f"{len(lines)} stderr lines")
        elif named not in lines[0]:
            problems.append(f"does not name {named!r}")
        if snapshot(cwd) != before:
            problems.append(f"changed the directory: {sorted(set(snapshot(cwd)) ^ set(before))}")
        if problems:
            failures.append(f"nift {' '.join(args)}: {', '.join(problems)}: {r.stderr.strip()[:300]!r}")
    assert not failures, "\n".join(failures)
    assert not (tmp_path / "logs").exists()  # no bad input counted as an internal error
