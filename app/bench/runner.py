"""Running a benchmark: trials as Ray tasks (app.fanout), a results file that grows one trial at a time, resume.

`out/run.json` records the run's settings; `out/results.jsonl` gets one line per (trial, method)
as soon as a trial is done. Starting again with the same settings skips finished trials (a
half-written last line from an interruption is ignored); other settings in the same directory are
refused. Trials run index-major (trial 1 of every task and pose, then trial 2, ...), so a run
stopped early - by its `minutes` budget or Ctrl-C - already makes a balanced table. Demo subsets
(--demos N < 10) and fused-camera demos are written to `out/demos/<task>/` (app.bench.demos), and
every template is built before the workers start, so that no two workers build the same one.
The demo folder (templates included) and other field weights travel to the workers as parcels
(app.fanout.shipping), so a cluster's nodes need only the project installed.
"""
from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Callable

from app.bench.demos import bench_demos
from app.fanout.cluster import ClusterConfig
from app.fanout.run import Outcome, fan_out
from app.fanout.shipping import Parcel, landed, pack
from app.bench.protocol import BenchConfig, Trial, trials
from app.io_utils import write_json
from app.nift.template import weights_id
from app.predict.methods import method as method_record
from app.tasks.demo_library import task_templates
from app.tasks.demo_library import DEMOS_DIR
from app.tasks.task import task

FORMAT = "nift-bench/1"
ADDED = {"place_demo_match": "mean", "align_grasp": False, "objects": [], "demo_dir": None}  # settings added since the format, with the value runs made before them had
RECYCLE_AFTER = 50  # trials a worker process runs before a fresh one replaces it (memory stays bounded)


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


@dataclass(frozen=True)
class Shipment:
    """What every worker needs: the settings, the demo folder (shipped unless it is the project's own,
    which every node has installed) and other field weights (shipped)."""

    config: BenchConfig
    demos: Parcel | Path
    fields: Parcel | None = None


def shipment(config: BenchConfig, demo_root: Path) -> Shipment:
    own = demo_root.resolve() == DEMOS_DIR.resolve()
    return Shipment(config, demo_root if own else pack(demo_root), None if config.nif is None else pack(config.nif))


@dataclass
class Worker:
    """A worker process's bench (a world, or the sim cell) with the settings and demos it runs trials with."""

    bench: object
    config: BenchConfig
    demo_root: Path

    def close(self) -> None:
        self.bench.close()


def make_worker(sent: Shipment) -> Worker:
    """Unpack the shipment on this node and build the bench in this process (torch on one thread, in
    this process too: a worker is a core)."""
    import torch

    from app.bench.trial import ExecutedBench, TeleportedBench

    torch.set_num_threads(1)
    config = sent.config if sent.fields is None else replace(sent.config, nif=str(landed(sent.fields)))
    root = sent.demos if isinstance(sent.demos, Path) else landed(sent.demos)
    bench = ExecutedBench if config.setting == "executed" else TeleportedBench
    return Worker(bench(config.cell, config.objects), config, root)


def run_trial(worker: Worker, trial: Trial) -> list[dict]:
    return worker.bench.run(trial, worker.config, worker.demo_root)


def error_rows(trial: Trial, config: BenchConfig, error: str) -> list[dict]:
    """A trial whose task raised: a row per method naming the error (not counted as a trial, report.py)."""
    return [{"trial": trial.key, "task": trial.task, "pose": trial.pose, "index": trial.index, "method": m,
             "internal_error": error} for m in config.methods]


def run(config: BenchConfig, out: Path, workers: int | ClusterConfig = 2,
        progress: Callable[[int, int, int], None] = lambda d, n, f: None, minutes: float | None = None) -> list[dict]:
    """Run (or finish) a benchmark into `out`; return every row. `workers`: a count of local processes,
    or where to run (app.fanout.cluster); `progress(done, total, failed)`. With `minutes`, stop after
    that wall time (trials in flight are dropped; running again resumes)."""
    deadline = None if minutes is None else time.monotonic() + 60 * minutes
    cluster = workers if isinstance(workers, ClusterConfig) else ClusterConfig(workers)
    demo_root = prepare(config, out)
    todo = pending(config, out)
    _drop_partial_rows(out, {tr.key for tr in todo})
    total, done, failed = len(trials(config)), len(trials(config)) - len(todo), 0
    progress(done, total, failed)
    if not todo:
        return read_rows(out)
    with open(out / "results.jsonl", "a") as sink:
        outcomes = fan_out(run_trial, todo, make_worker, shipment(config, demo_root), cluster, RECYCLE_AFTER)
        try:
            for outcome in outcomes:
                sink.write("".join(json.dumps(r) + "\n" for r in _rows(outcome, todo, config)))
                sink.flush()
                done, failed = done + 1, failed + outcome.failed
                progress(done, total, failed)
                if deadline is not None and time.monotonic() > deadline:
                    break
        finally:
            outcomes.close()  # stops the workers (and a local Ray) when the loop ends early
    return read_rows(out)


def _rows(outcome: Outcome, todo: list[Trial], config: BenchConfig) -> list[dict]:
    return error_rows(todo[outcome.index], config, outcome.error) if outcome.failed else outcome.value


def _drop_partial_rows(out: Path, keys: set[str]) -> None:
    """Rewrite results.jsonl without rows of trials about to run again (and any torn last line)."""
    path = out / "results.jsonl"
    if not path.exists():
        return
    kept = [r for r in read_rows(out) if r["trial"] not in keys]
    tmp = path.with_suffix(".tmp")
    tmp.write_text("".join(json.dumps(r) + "\n" for r in kept))
    tmp.replace(path)
