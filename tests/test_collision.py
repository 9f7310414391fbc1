import numpy as np
import pybullet as p
import pytest

from app import objects
from app.objects.collision import read_parts_obj


@pytest.fixture
def bullet():
    client = p.connect(p.DIRECT)
    yield client
    p.disconnect(client)


@pytest.mark.slow
def test_mug_collision_model_keeps_handle_hole_and_cavity(bullet, nift_cache):
    mesh = objects.generate("mug", 2)
    sem = objects.semantics(mesh)
    path = objects.collision_model(mesh)
    assert path.parent == nift_cache / "collision"
    parts = read_parts_obj(path)
    assert len(parts) > 3
    assert all(np.isclose(part.volume, part.convex_hull.volume, rtol=1e-3) for part in parts)
    shape = p.createCollisionShape(p.GEOM_MESH, fileName=str(path), physicsClientId=bullet)
    p.createMultiBody(0, shape, physicsClientId=bullet)

    def blocked(a, b) -> bool:
        return p.rayTest(list(a), list(b), physicsClientId=bullet)[0][0] >= 0

    c, axis = np.array(sem.handle_center), np.array(sem.handle_axis)
    r = 0.8 * objects.fixtures.RACK_PEG_RADIUS
    for offset in ([0, 0, 0], [r, 0, 0], [-r, 0, 0], [0, 0, r], [0, 0, -r]):
        assert not blocked(c + offset - 0.1 * axis, c + offset + 0.1 * axis), "handle hole filled"
    assert blocked([0, -0.2, sem.height / 2], [0, 0.2, sem.height / 2]), "wall missing"
    assert not blocked([0, 0, sem.height + 0.05], [0, 0, sem.params["bottom"] + 0.002]), "cavity filled"
    # a second call is served from the cache, unchanged
    mtime = path.stat().st_mtime_ns
    assert objects.collision_model(mesh) == path and path.stat().st_mtime_ns == mtime
