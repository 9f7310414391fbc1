"""The planning scene's broad phase (bounding boxes) changes no answer: every contact it names is the
one PyBullet's closest-point query names when asked about every link pair and every obstacle."""
import numpy as np
import pytest

from app.motion.scene import ARM_LINKS, HELD, ON_TABLE, PlanningScene
from hardware.bullet import p, set_pose
from hardware.robot_description import HOME_Q
from hardware.se3 import random_poses


@pytest.fixture(scope="module")
def scene():
    s = PlanningScene()
    rng = np.random.default_rng(5)
    s.add_cloud("object", rng.uniform([0.42, -0.08, 0.0], [0.58, 0.08, 0.12], (400, 3)), eye=np.array([0.0, 0.0, 1.5]))
    yield s
    s.close()


def _near(s: PlanningScene, a: int, b: int, link_a: int | None = None, link_b: int | None = None) -> bool:
    """Whether bodies a and b (or the given links of them; all links when None) are within the margin."""
    links = {"linkIndexA": link_a} if link_a is not None else {}
    links |= {"linkIndexB": link_b} if link_b is not None else {}
    return bool(p.getClosestPoints(a, b, s.margin, physicsClientId=s.client, **links))


def every_contact(s: PlanningScene, q: np.ndarray) -> set[str]:
    """The contacts at q from one query per link and obstacle, and per self pair: no broad phase."""
    s.set_q(q)
    found = {f"{link}-{name}" for name, body in s.obstacles.items() for link, index in s.links.items()
             if not (name == "table" and link in ON_TABLE) and _near(s, s.robot, body, link_a=index)}
    found |= {f"{a}-{b}" for a, b in s.self_pairs if _near(s, s.robot, s.robot, s.links[a], s.links[b])}
    if s.held is not None:
        body, T_tcp_body = s.held
        set_pose(s.client, body, s.kinematics.fk(q) @ T_tcp_body)
        found |= {f"{HELD}-{name}" for name, other in s.obstacles.items() if _near(s, body, other)}
        found |= {f"{HELD}-{link}" for link in ARM_LINKS if _near(s, body, s.robot, link_b=s.links[link])}
    return found


def test_the_contacts_are_those_of_every_pair_queried(scene):
    rng = np.random.default_rng(0)
    qs = HOME_Q + rng.uniform(-2.5, 2.5, (400, 6))
    T_grasp = scene.kinematics.fk(HOME_Q)
    T_grasp[:3, 3] = [0.5, 0.0, 0.06]
    for holding in (False, True):
        with (scene.holding("object", T_grasp) if holding else scene.fingers(scene.finger_width)):
            found = [set(scene.collisions(q)) for q in qs]
            assert found == [every_contact(scene, q) for q in qs]
    kinds = {hit.split("-")[-1] for hits in found for hit in hits}
    assert {"table", "object", "rack"} <= kinds and any(h.startswith(f"{HELD}-") for hs in found for h in hs)
    assert any(f"{a}-{b}" in hs for hs in found for a, b in scene.self_pairs)  # self contacts are in the sample


def test_the_free_gripper_names_what_every_obstacle_query_names(scene):
    rng = np.random.default_rng(1)
    hits = 0
    for T in random_poses(300, rng):
        T[:3, 3] = rng.uniform([0.3, -0.6, -0.05], [0.7, 0.6, 0.4])
        found = scene.gripper_collisions(T)
        expected = [name for name, body in scene.obstacles.items() if _near(scene, scene.ghost, body)]
        assert found == expected
        hits += bool(found)
    assert 30 < hits < 270
