"""The handle hole found in a mug's one-view cloud, and the hangs built from it (app.predict.handle_hole,
app.predict.hole_places): the generator's true hole, what shows no hole, rigid motions, the demos' own places."""
import numpy as np
import pytest

from app.nift.raycast import cast, make_scene
from app.objects import generate, semantics, split
from app.predict.pairs import Candidate
from app.predict.feasibility import demo_carries
from app.predict.handle_hole import HoleConfig, across, find_hole, fit_body, fits
from app.predict.hole_places import FLIPS, UP, demo_hang, demo_hole, hole_pairs, hole_places, with_hole_pairs
from app.tasks.demo_library import DEMOS_DIR, task_demos
from hardware.se3 import invert, make_pose, transform_points

CAMERA = np.array([-0.75, 0.0, 0.55])  # m, looking down at about 36 degrees onto an object at the origin


def yaw(angle: float, at=(0.0, 0.0, 0.0)) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return make_pose(np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]), at)


def one_view(mesh, T: np.ndarray, n: int = 30000, seed: int = 0) -> np.ndarray:
    """The points (M, 3) of `mesh` posed at T that CAMERA sees: surface samples with a clear line of sight."""
    posed = mesh.copy()
    posed.apply_transform(T)
    points = np.asarray(posed.sample(n, seed=seed))  # (n, 3)
    ray = points - CAMERA
    dist = np.linalg.norm(ray, axis=1)
    hit = cast(make_scene(posed.vertices, posed.faces), np.column_stack([np.tile(CAMERA, (n, 1)), ray / dist[:, None]]))
    return points[np.abs(hit - dist) < 1e-4]


def mug(index: int, scale: float = 1.0):
    mesh = generate("mug", split("mug", "test")[index])
    mesh.apply_scale(scale)
    return mesh, np.array(semantics(mesh).handle_center) * scale


@pytest.mark.parametrize("index,turn", [(0, np.pi / 2), (1, -np.pi / 2), (2, 2.2), (3, -1.2)])
def test_a_handle_in_view_gives_the_generators_hole(index, turn):
    """A test-split mug standing with its handle turned `turn` from the camera's line: the hole's centre
    within 5 mm of the generator's, its radial direction within 10 degrees, its axis the table's normal."""
    mesh, centre = mug(index)
    T = yaw(turn, (0.05, -0.02, 0.0))
    hole = find_hole(one_view(mesh, T), [0.0, 0.0, 1.0], up=UP)
    assert hole is not None
    assert np.linalg.norm(hole.T[:3, 3] - transform_points(T, centre[None])[0]) < 0.005
    assert hole.T[:3, 0] @ T[:3, 0] > np.cos(np.radians(10))
    np.testing.assert_allclose(hole.T[:3, 2], UP, atol=1e-12)


@pytest.mark.parametrize("index", [0, 1, 2])
def test_a_handle_behind_the_mug_gives_no_hole(index):
    """Handle turned straight away from the camera: nothing outside the body, no hole."""
    mesh, _ = mug(index)
    assert find_hole(one_view(mesh, yaw(0.0)), [0.0, 0.0, 1.0], up=UP) is None


def test_a_bowl_has_no_hole():
    bowl = generate("bowl", split("bowl", "test")[0])
    assert find_hole(one_view(bowl, yaw(0.7)), [0.0, 0.0, 1.0], up=UP) is None


def side_view(half: float, handle_azimuth: float, radius: float = 0.04, height: float = 0.09, reach: float = 0.03,
              n: int = 3000, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Points (M, 3) of one side of a cylindrical body (azimuths within +-half of x) and a handle loop
    beside it at `handle_azimuth`, as a held mug shows itself to a camera above; and the loop's centre."""
    rng = np.random.default_rng(seed)
    a, z = rng.uniform(-half, half, n), rng.uniform(0.0, height, n)
    body = np.column_stack([radius * np.cos(a), radius * np.sin(a), z])  # (n, 3)
    u, up = np.array([np.cos(handle_azimuth), np.sin(handle_azimuth), 0.0]), np.array([0.0, 0.0, 1.0])
    centre = (radius + 0.45 * reach) * u + height / 2 * up
    t = rng.uniform(0.0, 2 * np.pi, n // 3)
    loop = centre + (reach / 2 * np.cos(t))[:, None] * u + (0.65 * reach * np.sin(t))[:, None] * up  # (n/3, 3)
    return np.vstack([body, loop[np.linalg.norm(loop[:, :2], axis=1) > radius + 0.002]]), centre


@pytest.mark.parametrize("half,azimuth", [(30, 15), (40, 15), (40, 25), (40, 35)])
def test_a_shallow_side_view_is_refitted_and_gives_the_hole(half, azimuth):
    """One side of a body with its handle beside it: the algebraic circle's fit is no body (the case the
    refit is for), and the refit's hole lies within 5 mm of the loop's centre."""
    points, centre = side_view(np.radians(half), np.radians(azimuth))
    q = points - points.mean(axis=0)
    flat, h = q @ across(UP), q @ UP
    assert not fits(fit_body(flat, h, HoleConfig()), flat, h, HoleConfig())
    hole = find_hole(points, [0.0, 0.0, 1.0], up=UP)
    assert hole is not None
    assert np.linalg.norm(hole.T[:3, 3] - centre) < 0.005


def test_the_hole_moves_with_the_mug():
    """Turning the cloud about the table's normal and moving it turns and moves the hole's frame alike."""
    mesh, _ = mug(0)
    cloud = one_view(mesh, yaw(np.pi / 2))
    M = yaw(0.8, (0.1, 0.2, 0.0))
    a = find_hole(cloud, [0.0, 0.0, 1.0], up=UP)
    b = find_hole(transform_points(M, cloud), [0.0, 0.0, 1.0], up=UP)
    np.testing.assert_allclose(b.T, M @ a.T, atol=1e-6)


def test_the_axis_points_to_the_rim_side_named():
    mesh, _ = mug(0)
    cloud = one_view(mesh, yaw(np.pi / 2))
    up, down = find_hole(cloud, [0.0, 0.0, 1.0], up=UP), find_hole(cloud, [0.0, 0.0, -1.0], up=UP)
    np.testing.assert_allclose(down.T[:3, 2], -up.T[:3, 2], atol=1e-12)
    np.testing.assert_allclose(down.T[:3, 3], up.T[:3, 3], atol=1e-9)  # the same hole


@pytest.fixture(scope="module")
def demos():
    return task_demos(DEMOS_DIR / "mug")


def test_a_demo_with_its_hole_gets_its_own_place_back(demos):
    """A demo whose cloud shows the hole, alone: its hole place is its own place (T_base_fixture_seen)."""
    d = next(d for d in demos if find_hole(d.cloud, d.T_base_tcp[:3, 3], up=UP) is not None)
    places = hole_places(find_hole(d.cloud, d.T_base_tcp[:3, 3], up=UP), demo_hole([d]))
    np.testing.assert_allclose(places[0], d.place_anchor(), atol=1e-9)


def test_the_demos_hang_the_hole_on_the_peg_as_the_teacher_did(demos):
    """The shipped demos (the teacher's hangs, app.tasks.teacher.hang_pose) put the hole's centre 60 %
    of the way along the peg, its axis on the peg: the mean seen from their clouds within 6 mm and 5 degrees."""
    from app.objects import fixture
    rack = fixture("rack")
    d = np.array(rack.landmarks["peg_direction"])
    point = np.array(rack.landmarks["peg_origin"]) + 0.6 * rack.landmarks["peg_length"] * d
    T = demo_hole(demos)
    assert np.linalg.norm(T[:3, 3] - point) < 0.006
    assert T[:3, 1] @ d > np.cos(np.radians(5))


def test_both_hangs_put_the_hole_in_the_same_place_facing_either_way(demos):
    mesh, _ = mug(1)
    hole = find_hole(one_view(mesh, yaw(-np.pi / 2)), [0.0, 0.0, 1.0], up=UP)
    T_fixture_hole = demo_hole(demos)
    places = hole_places(hole, T_fixture_hole, turns=(0.0, 0.5))
    assert len(places) == 4
    for F, seen in zip(FLIPS, places[:2]):
        np.testing.assert_allclose(invert(seen) @ hole.T @ F, T_fixture_hole, atol=1e-9)
    for F, seen in zip(FLIPS, places[2:]):  # swung about the peg: the hole's centre and axis stay on it
        swung = invert(seen) @ hole.T @ F  # (4, 4) the hole in the fixture's frame
        np.testing.assert_allclose(swung[:3, 3], T_fixture_hole[:3, 3], atol=1e-9)
        np.testing.assert_allclose(swung[:3, 1], T_fixture_hole[:3, 1], atol=1e-9)
        assert swung[:3, 0] @ T_fixture_hole[:3, 0] == pytest.approx(np.cos(0.5))


def test_hole_pairs_come_first_and_only_where_the_grasp_carries_like_the_demos(demos):
    d = demos[0]
    grasp = Candidate(d.T_base_tcp, d.place_anchor(), d.T_base_fixture, 0.0, 0, 0)
    higher = make_pose(np.eye(3), 0.3 * d.place_anchor()[:3, 2])  # 30 cm up the fixture's z: no demo carried so
    far = Candidate(higher @ d.T_base_tcp, d.place_anchor(), d.T_base_fixture, 0.1, 1, 0)
    places = np.stack([d.place_anchor(), d.place_anchor() @ make_pose(np.eye(3), [0.0, 0.0, 0.5])])
    assert [(p.grasp_rank, p.place_rank) for p in hole_pairs([far, grasp], places[::-1], demo_carries(demos))] == [(0, -2)]
    pairs = hole_pairs([grasp, far], places, demo_carries(demos))
    assert [(p.grasp_rank, p.place_rank) for p in pairs] == [(0, -1)]  # its own carry; the rest carry 20-50 cm off the demos'
    mesh, _ = mug(0)
    options, found = with_hole_pairs([grasp], one_view(mesh, yaw(0.0)), demo_hang(demos))  # the handle hidden
    assert options == [grasp] and found["found"] is False
