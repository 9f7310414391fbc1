"""Running a benchmark: worker processes, a results file that grows one trial at a time, resume.

`out/run.json` records the run's settings; `out/results.jsonl` gets one line per (trial, method)
as soon as a trial is done. Starting again with the same settings skips finished trials (a
half-written last line from an interruption is ignored); other settings in the same directory are
refused. Trials run index-major (trial 1 of every task and pose, then trial 2, ...), so a run
stopped early - by its `minutes` budget or Ctrl-C - already makes a balanced table. Demo subsets
(--demos N < 10) and fused-camera demos are written to `out/demos/<task>/` (app.bench.demos), and
every template is built before the workers start, so that no two workers build the same one.
"""
from __future__ import annotations

import json
import multiprocessing as mp
import os
import time
from dataclasses import asdict
from pathlib import Path
from typing import Callable

from app.bench.demos import bench_demos
from app.bench.protocol import BenchConfig, Trial, trials
from app.io_utils import write_json
from app.nift.template import weights_id
from app.predict.methods import method as method_record
from app.tasks.demo_library import task_templates
from app.tasks.task import task
from app.workers import die_with_parent

FORMAT = "nift-bench/1"
ADDED = {"place_demo_match": "mean", "align_grasp": False, "objects": [], "demo_dir": None}  # settings added since the format, with the value runs made before them had
_worker = None  # the per-process bench (a world, or the sim cell), made by _init_worker


def settings(config: BenchConfig) -> dict:
    """What must match for a resume: everything but the cell's object identity."""
    d = asdict(config)
    d["cell"] = repr(config.cell)
    d["nif"] = config.fields  # as resolved: a fused run names the fused fields
    d["align_grasp"] = config.aligns  # as resolved: on with fused cameras
    if config.fields is not None:
        d["nif_id"] = weights_id(config.fields)  # the hash: other weights at the same path do not resume
    return {"format": FORMAT, **d}


def prepare(config: BenchConfig, out: Path) -> Path:
    """Check the settings against an earlier run in `out`; build every template; return the demo root."""
    config.check()
    for method in config.methods:
        method_record(method)
    out.mkdir(parents=True, exist_ok=True)
    run_file = out / "run.json"
    wanted = json.loads(json.dumps(settings(config)))
    if run_file.exists():
        try:
            recorded = json.loads(run_file.read_text())
        except (json.JSONDecodeError, UnicodeDecodeError):
            recorded = None
        if not isinstance(recorded, dict):
            raise ValueError(f"{run_file} is not a run record (torn or not a JSON object); remove it or choose another --out")
        earlier = {**ADDED, **recorded}  # an older run: what it did then
        if {**earlier, "trials": None} != {**wanted, "trials": None}:
            raise ValueError(f"{out} holds results of a run with other settings; choose another --out")
        if not isinstance(earlier.get("trials"), int):
            raise ValueError(f"{run_file} records no number of trials; remove it or choose another --out")
        if config.trials < earlier["trials"]:
            raise ValueError(f"{out} holds a run of {earlier['trials']} trials per task and pose; "
                             f"ask for at least that many or choose another --out")
    read_rows(out)  # a results file with a foreign line is refused before anything is written
    # more trials than before extend the run: a trial's seed depends on its index alone (protocol.py)
    write_json(run_file, wanted)
    root = bench_demos(config, out)
    for name in config.tasks:
        t = task(name)
        for method in config.methods:
            if (m := method_record(method)).template:
                task_templates(t, root / t.demos, m.query, m.feature, nif=config.fields)
    return root


def read_rows(out: Path) -> list[dict]:
    """Rows written so far (a truncated last line is dropped)."""
    path = out / "results.jsonl"
    if not path.exists():
        return []
    rows = []
    for number, line in enumerate(path.read_text().splitlines(), 1):
        try:
            row = json.loads(line)
        except json.JSONDecodeError:
            break  # an interrupted write: that trial runs again
        if not isinstance(row, dict) or not isinstance(row.get("trial"), str) or not isinstance(row.get("method"), str):
            raise ValueError(f"{path} line {number} is not a result row (a JSON object with a trial and a method); "
                             f"remove it or give another --out")
        rows.append(row)
    return rows


def pending(config: BenchConfig, out: Path) -> list[Trial]:
    """Trials with a row missing for some method."""
    have: dict[str, set[str]] = {}
    for row in read_rows(out):
        have.setdefault(row["trial"], set()).add(row["method"])
    return [tr for tr in trials(config) if not set(config.methods) <= have.get(tr.key, set())]


def _init_worker(config: BenchConfig, demo_root: Path, parent: int | None = None) -> None:
    """Set up this process's bench (`parent`: the pid of the command that spawned it, which it dies with)."""
    global _worker
    import torch

    if parent is not None:
        die_with_parent(parent)
    from app.bench.trial import ExecutedBench, TeleportedBench

    torch.set_num_threads(1)
    bench = ExecutedBench if config.setting == "executed" else TeleportedBench
    _worker = (bench(config.cell, config.objects), config, demo_root)


def _run_trial(trial: Trial) -> list[dict]:
    bench, config, demo_root = _worker
    return bench.run(trial, config, demo_root)


def run(config: BenchConfig, out: Path, workers: int = 2, progress: Callable[[int, int], None] = lambda d, n: None,
        minutes: float | None = None) -> list[dict]:
    """Run (or finish) a benchmark into `out`; return every row. With `minutes`, stop after that wall time
    (trials in flight are dropped; running again resumes)."""
    deadline = None if minutes is None else time.monotonic() + 60 * minutes
    demo_root = prepare(config, out)
    todo = pending(config, out)
    _drop_partial_rows(out, {tr.key for tr in todo})
    total, done = len(trials(config)), len(trials(config)) - len(todo)
    progress(done, total)
    if todo:
        with open(out / "results.jsonl", "a") as sink:
            if workers <= 1:
                _init_worker(config, demo_root)
                results = map(_run_trial, todo)
            else:
                pool = mp.get_context("spawn").Pool(workers, _init_worker, (config, demo_root, os.getpid()))
                results = pool.imap_unordered(_run_trial, todo)
            try:
                for rows in results:
                    sink.write("".join(json.dumps(r) + "\n" for r in rows))
                    sink.flush()
                    done += 1
                    progress(done, total)
                    if deadline is not None and time.monotonic() > deadline:
                        break
            finally:
                if workers > 1:
                    pool.terminate()
                else:
                    _close_worker()
    return read_rows(out)


def _close_worker() -> None:
    """Free the in-process bench (its physics clients) after a single-process run."""
    global _worker
    if _worker is not None:
        _worker[0].close()
        _worker = None


def _drop_partial_rows(out: Path, keys: set[str]) -> None:
    """Rewrite results.jsonl without rows of trials about to run again (and any torn last line)."""
    path = out / "results.jsonl"
    if not path.exists():
        return
    kept = [r for r in read_rows(out) if r["trial"] not in keys]
    tmp = path.with_suffix(".tmp")
    tmp.write_text("".join(json.dumps(r) + "\n" for r in kept))
    tmp.replace(path)
