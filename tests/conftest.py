import os

import numpy as np
import pytest

if os.environ.get("PYTEST_XDIST_WORKER"):  # one of the suite's workers (`-n 2`): one core each, for the
    # worker and the `nift` commands it starts, as the cell runs torch (JobConfig.threads)
    for name in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ[name] = "1"


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(1234)


@pytest.fixture(scope="session")
def true_calibration(tmp_path_factory):
    """A calibration file holding the simulated camera's true pose, for end-to-end tests whose subject
    is not the calibration (that is tested on its own, tests/test_cli.py): each would calibrate first."""
    from app.simcell.cell import CellConfig, SimCell
    from calibration.store import save_calibration

    with SimCell(CellConfig()) as cell:
        return save_calibration(tmp_path_factory.mktemp("calibration") / "calibration.json",
                                np.array(cell.camera.config.T_base_cam), {})


@pytest.fixture
def nift_cache(tmp_path, monkeypatch):
    """A private, empty cache directory so collision models are really computed."""
    monkeypatch.setenv("NIFT_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.fixture
def teacher_grasp_verdicts():
    """judge(category, T_tcp_offset, refinements) -> the grasp judge's verdict for each refinement
    ((T_world_tcp, cloud) -> T_world_tcp) of the scripted teacher's grasp on the first upright test
    object, moved by T_tcp_offset (TCP frame); the cloud is 20,000 points of the object's surface."""
    from app.objects import split
    from app.simcell.judges import judge_grasp
    from app.simcell.spawn import spawn
    from app.tasks.task import teacher_grasp
    from hardware.se3 import make_pose, transform_points
    from hardware.sim.world import SimWorld, SimWorldConfig

    world = SimWorld(SimWorldConfig())
    world.connect()

    def judge(category, T_tcp_offset, refinements):
        verdicts = []
        for refine in refinements:
            obj = spawn(world, category, split(category, "test")[0], "upright",
                        T_world_obj=make_pose(np.eye(3), [0.5, 0.0, 0.0]))
            T_world_obj = world.pose(obj.body)
            cloud = transform_points(T_world_obj, obj.mesh.sample(20000, seed=0))
            verdicts.append(judge_grasp(world, obj, refine(T_world_obj @ teacher_grasp(obj.mesh) @ T_tcp_offset, cloud)))
            world.remove(obj.body)
        return verdicts

    yield judge
    world.disconnect()
