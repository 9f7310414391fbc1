"""Run `nift` cases as forked children of one interpreter that imported the CLI and its heavy modules
once (tests/test_bad_inputs.py): each case is still its own process - its working directory, its exit
code, its stdout and stderr - as a user's `nift` is, without paying the imports (~2 s) a hundred times.

    python tests/cli_forkserver.py CASES.json RESULTS.json

CASES.json: [{"args": [...], "cwd": DIR, "stdout": FILE, "stderr": FILE}, ...]; RESULTS.json: the exit
codes, in order. Two cases run at a time (this machine's cores)."""
from __future__ import annotations

import importlib
import json
import os
import sys

# what the verbs import lazily, once their arguments are checked
PRELOAD = ("app.cli", "torch", "pybullet", "trimesh", "app.simcell.cell", "app.simcell.sim_job", "app.jobs.job",
           "app.predict.predict", "app.bench.protocol", "app.training.train", "app.training.data", "app.teach.page")
AT_ONCE = 2


def child(case: dict) -> int:
    """In the forked child: the case's directory and output files, then `nift` itself."""
    from app.cli import main

    os.chdir(case["cwd"])
    for fd, name in ((1, case["stdout"]), (2, case["stderr"])):
        os.dup2(os.open(name, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644), fd)
    sys.argv = ["nift", *case["args"]]
    try:
        code = main(case["args"])
    except SystemExit as exc:  # argparse's exits
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    sys.stdout.flush()
    sys.stderr.flush()
    return int(code or 0)


def run_all(cases: list[dict]) -> list[int]:
    """Fork a child per case, AT_ONCE at a time; their exit codes in the cases' order."""
    codes: list[int | None] = [None] * len(cases)
    running: dict[int, int] = {}  # pid -> case index
    for i, case in enumerate(cases):
        while len(running) >= AT_ONCE:
            pid, status = os.wait()
            codes[running.pop(pid)] = os.waitstatus_to_exitcode(status)
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:
            try:
                os._exit(child(case))
            except BaseException:  # noqa: BLE001 - never return into the server's loop
                os._exit(70)
        running[pid] = i
    while running:
        pid, status = os.wait()
        codes[running.pop(pid)] = os.waitstatus_to_exitcode(status)
    return codes


if __name__ == "__main__":
    for name in PRELOAD:
        importlib.import_module(name)
    cases_file, results_file = sys.argv[1:3]
    with open(cases_file) as f:
        results = run_all(json.load(f))
    with open(results_file, "w") as f:
        json.dump(results, f)
