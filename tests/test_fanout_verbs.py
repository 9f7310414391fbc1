"""The verbs that fan out, on a real Ray: two local workers write what one process writes (make-data,
bench-jobs, bench-imitation; bench in tests/test_bench.py), and a two-node cluster on this machine runs a bench through
--address, the demos shipped to it through the object store."""
import json

import numpy as np
import psutil
import pytest

from app.bench.imitation import run_imitation_benchmark
from app.cli import main
from app.fanout.cluster import ClusterConfig, warmed
from app.fanout.guard import is_ray
from app.training.data import DataConfig, make_dataset

pytestmark = pytest.mark.slow

WALL_TIMES = ("seconds", "total_seconds", "planning_seconds")  # what differs between two runs of the same job


def timeless(value):
    """A record without its wall-clock times, at any depth."""
    if isinstance(value, dict):
        return {k: timeless(v) for k, v in value.items() if k not in WALL_TIMES}
    if isinstance(value, list):
        return [timeless(v) for v in value]
    return value


def test_make_data_on_two_workers_writes_the_bytes_one_process_writes(tmp_path):
    config = DataConfig(instances=2, views=2, queries=200, shard_instances=1, seed=5)
    one = make_dataset(config, tmp_path / "one", workers=1, progress=False)
    with warmed(ClusterConfig(2)) as ready:
        ready.startup.join()  # Ray up first: its workers make every shard (the command would make these few itself)
        two = make_dataset(config, tmp_path / "two", workers=ready, progress=False)
    assert one.manifest["complete"] and two.manifest["complete"] and len(one.manifest["shards"]) == 6
    for shard in one.manifest["shards"]:
        a, b = np.load(tmp_path / "one" / shard["file"]), np.load(tmp_path / "two" / shard["file"])
        assert set(a.files) == set(b.files) and all(np.array_equal(a[k], b[k]) for k in a.files)
    assert timeless(one.manifest["shards"]) == timeless(two.manifest["shards"])


def test_bench_jobs_on_two_workers_records_what_one_process_records(tmp_path, true_calibration):
    records = {}
    for workers in (1, 2):
        records[workers] = tmp_path / f"records-{workers}.json"
        assert main(["bench-jobs", "--tasks", "bowl", "--jobs", "2", "--workers", str(workers), "--calibration",
                     str(true_calibration), "--records", str(records[workers]), "--json"]) == 0
    one, two = (json.loads(records[w].read_text()) for w in (1, 2))
    assert [r["seed"] for r in one] == [0, 1] and all(r["success"] for r in one)
    assert timeless(two) == timeless(one)


def test_bench_imitation_on_two_workers_measures_what_one_process_measures():
    one = run_imitation_benchmark(quick=True, tasks=("bowl", "bottle"), schedule="cell")
    two = run_imitation_benchmark(quick=True, tasks=("bowl", "bottle"), schedule="cell", cluster=ClusterConfig(2))
    timed = ("seconds_per_prediction", "seconds_per_template", "workers")
    assert one["workers"] == 1 and two["workers"] == 2 and one["bowl_failed"] == two["bottle_failed"] == 0
    assert {k: v for k, v in one.items() if not k.endswith(timed)} == {k: v for k, v in two.items()
                                                                       if not k.endswith(timed)}
    assert one["bowl_grasp_error_mm"] < 50  # a prediction, not an empty row


def test_a_two_node_cluster_runs_a_bench_through_its_address_and_another_ray_is_refused(tmp_path, monkeypatch):
    import ray._private.utils
    from ray.cluster_utils import Cluster

    from app.fanout.cluster import ClusterConfig, ClusterError, started

    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
    cluster.add_node(num_cpus=1)
    try:
        ours = ray._private.utils.compute_version_info()
        with monkeypatch.context() as m:  # this command as if it ran another Ray than the cluster's
            m.setattr(ray._private.utils, "compute_version_info", lambda: ("2.0.0", ours[1]))
            with pytest.raises(ClusterError, match=f"--address {cluster.address}: Version mismatch"):
                with started(ClusterConfig(2, cluster.address)):
                    pass
        args = ["bench", "--tasks", "bowl", "--methods", "cpd", "--trials", "2", "--poses", "upright", "--demos", "5",
                "--json"]  # five demos: a demo folder of the run's own, shipped to the nodes
        assert main([*args, "--out", str(tmp_path / "cluster"), "--address", cluster.address]) == 0
        nodes = len(cluster.list_all_nodes())
    finally:
        cluster.shutdown()
    assert main([*args, "--out", str(tmp_path / "here"), "--workers", "1"]) == 0
    rows = {d: [timeless(json.loads(line)) for line in (tmp_path / d / "results.jsonl").read_text().splitlines()]
            for d in ("cluster", "here")}
    assert nodes == 2 and len(rows["here"]) == 2
    assert sorted(map(json.dumps, rows["cluster"])) == sorted(map(json.dumps, rows["here"]))
    assert not [p for p in psutil.Process().children(recursive=True) if is_ray(p)]  # nothing of Ray left


def test_a_set_imported_on_two_workers_stores_what_one_import_stores_and_names_a_bad_file(tmp_path):
    import trimesh

    from app.fanout.cluster import ClusterConfig
    from app.objects.library import import_object, load_object
    from app.objects.shape_set import import_set

    trimesh.creation.cylinder(radius=0.04, height=0.2, sections=24).export(tmp_path / "can.stl")
    trimesh.creation.box((0.06, 0.04, 0.18)).export(tmp_path / "carton.stl")
    (tmp_path / "broken.stl").write_bytes(b"solid nothing\nendsolid\n")
    entries = [("can", "can.stl"), ("carton", "carton.stl"), ("broken", "broken.stl")]
    (tmp_path / "set.toml").write_text("".join(f'[[object]]\nname = "{n}"\ncategory = "bottle"\nfile = "{f}"\nunits = "m"\n\n'
                                               for n, f in entries))
    with pytest.raises(ValueError, match=r"1 of 3 meshes could not be imported \(broken.stl: "):
        import_set(tmp_path / "set.toml", tmp_path / "ray", cluster=ClusterConfig(2))
    import_object(tmp_path / "can.stl", "bottle", "can", units="m", directory=tmp_path / "here")
    there, here = load_object("can", tmp_path / "ray"), load_object("can", tmp_path / "here")
    assert (tmp_path / "ray" / "carton" / "object.json").is_file() and not (tmp_path / "ray" / "broken").exists()
    for part in ("mesh.obj", "collision.obj"):
        assert (tmp_path / "ray" / "can" / part).read_bytes() == (tmp_path / "here" / "can" / part).read_bytes()
    assert there.collision.read_bytes() == here.collision.read_bytes()
    assert json.loads((tmp_path / "ray" / "can" / "object.json").read_text())["source"] == str(tmp_path / "can.stl")
