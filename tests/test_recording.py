"""A job as a Rerun recording (`app.recording`), read back with Rerun's own reader (`rerun.chunk.RrdReader`):
a job on fake devices (tests/test_job_branches.py's cell) written to an .rrd, then its entities, its
timeline, the TCP at the grasp and the candidates checked against the job's record."""
from __future__ import annotations

import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest

from app.recording.layout import outcome_colour
from app.io_utils import numbered
from app.recording.target import check_target
from test_job_branches import Cell, grasp, predictor_of, run  # noqa: F401 - the fixtures `cell` and `scene` too
from test_job_branches import cell, scene  # noqa: F401

ROOT = Path(__file__).resolve().parents[1]


def read_back(path: Path) -> dict[str, list[dict]]:
    """Every entity's rows, {entity path: [{column: value}]}, from the recording's chunks; a time
    column's values in seconds."""
    import pyarrow as pa
    import rerun.chunk as ch

    def values(column: pa.Array) -> list:
        if pa.types.is_duration(column.type) or pa.types.is_timestamp(column.type):
            return [None if v is None else v / 1e9 for v in column.cast(pa.int64()).to_pylist()]
        return column.to_pylist()

    rows: dict[str, list[dict]] = defaultdict(list)
    for chunk in ch.RrdReader(path).store().stream().to_chunks():
        batch = chunk.to_record_batch()
        columns = {name: values(batch.column(i)) for i, name in enumerate(batch.schema.names)}
        rows[chunk.entity_path] += [{k: v[r] for k, v in columns.items()} for r in range(batch.num_rows)]
    return rows


@pytest.fixture
def recorded(cell, scene, tmp_path):
    """(record, rows) of a job whose first grasp is ruled out (its fingers in the table) and whose second
    succeeds, recorded to tmp_path/job.rrd."""
    from app.recording.job_log import RerunJobLog

    path = tmp_path / "job.rrd"
    result = run(cell, scene, predictor_of(grasp(down=0.125), grasp(0.5)), job_log=RerunJobLog(path))
    assert result.success, result.reason
    return result.record(), read_back(path)


def test_the_recording_holds_the_layouts_entities(recorded):
    record, rows = recorded
    expected = {"/world/cloud/first_look", "/world/camera", "/camera/image", "/camera/depth", "/world/prediction/grasp",
                "/world/nit/grasp", "/world/nit/place", "/world/plan/grasp", "/world/plan/path/carry", "/world/tcp",
                "/plots/joints/j1", "/plots/joints/j6", "/plots/gripper/width", "/plots/gripper/force", "/plots/tool/force", "/job/stages",
                "/job/verdict", "/robot/joints/elbow_joint", "/world/fixtures/0"}
    assert expected <= set(rows), sorted(expected - set(rows))
    assert any(p.startswith("/robot") and "ur5" in p for p in rows)  # the URDF's meshes


def test_the_timeline_spans_the_job_from_its_first_stage_to_its_verdict(recorded, cell):
    record, rows = recorded
    stages = sorted((r["wall"], r["sim"], r["TextLog:text"][0]) for r in rows["/job/stages"])
    times = [t for _, t, _ in stages]
    assert [text for _, _, text in stages[:2]] == ["job: bottle by nift", "capture started"]
    assert stages[-1][2] == "verify ended" and times == sorted(times)  # the arm's clock only runs forward
    tcp_times = [r["sim"] for r in rows["/world/tcp"] if r.get("sim") is not None]
    assert min(tcp_times) >= min(times) - 1e-9 and max(tcp_times) == pytest.approx(max(times), abs=1e-6)
    assert max(times) - min(times) == pytest.approx(record["motion"]["motion_seconds"], abs=0.05)  # fake arm: only motions take time
    verdict = rows["/job/verdict"][0]["TextDocument:text"][0]
    assert "succeeded" in verdict and '"grasp_rank": 1' in verdict


def test_the_logged_tcp_at_the_grasp_is_the_records_grasp_pose(recorded):
    from hardware.se3 import ur_to_pose

    record, rows = recorded
    grasped = [r["sim"] for r in rows["/job/stages"] if r.get("TextLog:text") == ["grasp ended"]][-1]
    at = [r for r in rows["/world/tcp"] if r.get("sim") is not None and abs(r["sim"] - grasped) < 1e-6][-1]
    T = ur_to_pose(record["poses"]["grasp"])
    assert np.allclose(at["Transform3D:translation"][0], T[:3, 3], atol=1e-3)
    R = np.reshape(at["Transform3D:mat3x3"][0], (3, 3), order="F")  # Rerun stores a 3x3 column by column
    assert np.allclose(R, T[:3, :3], atol=1e-3)


def test_one_candidate_entity_per_candidate_of_the_record_with_its_outcome(recorded):
    record, rows = recorded
    drawn = sorted(p for p in rows if p.startswith("/world/candidates/") and
                   any("LineStrips3D:strips" in r for r in rows[p]))
    assert len(drawn) == len(record["candidates"]) >= 2
    for path, c in zip(drawn, record["candidates"]):
        [row] = [r for r in rows[path] if "outcome" in r]
        assert row["outcome"] == [c["outcome"]]
        [drawn_row] = [r for r in rows[path] if "LineStrips3D:colors" in r]
        red, green, blue = outcome_colour(c["outcome"])
        assert drawn_row["LineStrips3D:colors"][0] == (red << 24) | (green << 16) | (blue << 8) | 255  # RGBA, packed


def test_a_job_without_a_recording_never_imports_rerun():
    code = ("import sys; sys.path.insert(0, 'tests');"
            "from test_job_branches import *;"
            "from app.simcell.sim_job import run_sim_job; import app.commands.run;"
            "assert 'rerun' not in sys.modules, 'rerun imported'")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-500:]


def test_a_recording_target_is_checked_before_the_job(tmp_path):
    assert check_target(None) is None and check_target("spawn") is None
    assert check_target(str(tmp_path / "job.rrd")) == tmp_path / "job.rrd"
    for bad, why in ((tmp_path / "missing" / "job.rrd", "no folder"), (tmp_path / "job.txt", ".rrd file"),
                     (Path("/sys/job.rrd"), "cannot be written")):
        with pytest.raises(ValueError, match=why):
            check_target(str(bad))
    assert numbered(tmp_path / "a.rrd", 3, 5) == tmp_path / "a-03.rrd" and numbered(tmp_path / "a.rrd", 0, 1) == tmp_path / "a.rrd"


def test_the_index_of_a_series_groups_its_failed_jobs_by_stage():
    from app.bench.job_series import recording_name, recordings_index
    from app.jobs.record import JobResult
    from app.simcell.sim_job import JobSpec
    from app.tasks.task import task

    specs = [JobSpec(task("mug"), seed) for seed in range(4)]
    results = [JobResult("mug", "nift", success=True), JobResult("mug", "nift", failed_stage="place", reason="a"),
               JobResult("mug", "nift", failed_stage="grasp", reason="b"), JobResult("mug", "nift", failed_stage="place")]
    index = recordings_index(specs, results)
    assert recording_name(specs[1]) == "mug-upright-0001.rrd"
    assert index["failures_by_stage"] == {"place": ["mug-upright-0001.rrd", "mug-upright-0003.rrd"],
                                          "grasp": ["mug-upright-0002.rrd"]}
    assert [j["success"] for j in index["jobs"]] == [True, False, False, False]


def test_a_teach_in_session_is_recorded_step_by_step(tmp_path):
    """A session on the simulated cell, its steps told to a `SessionRecording`: one stage-log line per
    step (a refused one too), the TCP after the guide at the grasp, and the saved demo's grasp."""
    from app.recording.session_log import SessionRecording, session_path
    from app.simcell.cell import CellConfig, SimCell
    from app.tasks.task import task, teacher_grasp, teacher_place
    from app.teach.session import TeachSession
    from hardware.se3 import invert

    path = session_path(tmp_path / "bowl", now=0.0)
    assert path.parent == tmp_path and path.name.startswith("bowl-session-") and path.suffix == ".rrd"
    with SimCell(CellConfig()) as cell:
        session = TeachSession(cell, task("bowl"), tmp_path / "bowl", np.array(cell.camera.config.T_base_cam))
        recording = SessionRecording(path)
        session.observers.append(recording.step)
        try:
            assert session.new_object(instance=None).ok
            obj = session.current.obj
            grasp = session.current.T_base_obj @ teacher_grasp(obj.mesh)
            assert session.guide(grasp).ok and session.close_gripper().ok
            with pytest.raises(ValueError):
                session.close_gripper()  # refused: already held
            place = session.T_base_fixture @ teacher_place(task("bowl"), obj.mesh, obj.scale)
            assert session.guide(place @ invert(session.current.T_tcp_obj)).ok and session.release().ok
            assert session.save_demo().ok
        finally:
            recording.close()
            session.close()
    rows = read_back(path)
    lines = [r["TextLog:text"][0] for r in sorted(rows["/job/stages"], key=lambda r: r["step"])]
    assert [line.split(":")[0] for line in lines] == ["new_object", "guide", "close_gripper", "close_gripper",
                                                      "guide", "release", "save_demo"]
    assert "already held" in lines[3]
    [after_guide] = [r for r in rows["/world/tcp"] if r.get("step") == 2]
    assert np.allclose(after_guide["Transform3D:translation"][0], grasp[:3, 3], atol=2e-3)
    assert "/world/demos/demo-00/grasp" in rows and "/world/cloud/first_look" in rows


def test_without_a_viewer_to_spawn_the_recording_fails_in_one_line(monkeypatch):
    import rerun as rr

    from app.recording.job_log import RerunJobLog

    def no_viewer(**_):
        raise RuntimeError("Failed to find Rerun Viewer executable in PATH.\n\n    You can install ...")

    monkeypatch.setattr(rr, "spawn", no_viewer)
    with pytest.raises(FileNotFoundError, match="no Rerun viewer could be started") as err:
        RerunJobLog(None)
    assert "\n" not in str(err.value) and "Failed to find Rerun Viewer" in str(err.value)
