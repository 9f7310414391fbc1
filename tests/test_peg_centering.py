"""Peg centring: the analytic gap centre, what it leaves alone, and a real mug's hole put back on the peg."""
import numpy as np
import pytest

from app.objects import fixture, generate, semantics, split
from app.predict.peg_centering import LANE, center_on_peg, peg_frame, peg_shift
from app.tasks.teacher import hang_pose
from hardware.se3 import invert, make_pose, random_rotations, transform_points

RACK = fixture("rack")


def _arms(centre: float, half_gap: float, n: int = 60, seed: int = 0) -> np.ndarray:
    """Points (2n, 3), rack frame, of two walls across the peg's lane at v = centre -+ half_gap (5 mm thick)."""
    rng = np.random.default_rng(seed)
    o, d, e1, e2 = peg_frame(RACK)
    s = rng.uniform(0.03, 0.07, 2 * n)
    u = rng.uniform(-LANE / 2, LANE / 2, 2 * n)
    v = np.concatenate([rng.uniform(centre - half_gap - 0.005, centre - half_gap, n),
                        rng.uniform(centre + half_gap, centre + half_gap + 0.005, n)])
    v[0], v[n] = centre - half_gap, centre + half_gap  # the gap's exact edges
    return o + s[:, None] * d + u[:, None] * e1 + v[:, None] * e2


@pytest.mark.parametrize("centre", [-0.02, 0.0, 0.013])
def test_the_peg_moves_to_the_middle_of_the_gap(centre):
    assert peg_shift(_arms(centre, 0.02), RACK) == pytest.approx(centre, abs=1e-9)


def test_a_gap_narrower_than_the_peg_or_no_points_leave_the_pose_alone():
    assert peg_shift(_arms(0.01, 0.007), RACK) == 0.0  # 14 mm < 12 mm peg + 4 mm clearance
    assert peg_shift(np.zeros((0, 3)), RACK) == 0.0
    far = _arms(0.01, 0.02) + 0.05 * np.array([0.0, 0.0, 1.0])  # 5 cm above the lane
    assert peg_shift(far, RACK) == 0.0


def test_the_nearest_wide_gap_wins():
    o, d, e1, e2 = peg_frame(RACK)
    v = np.linspace(-0.055, 0.055, 1101)  # a wall across the lane every 0.1 mm, but for two holes
    v = v[(np.abs(v + 0.035) > 0.01) & (np.abs(v - 0.02) > 0.01)]  # 20 mm holes at -35 and +20 mm
    cloud = o + 0.05 * d + v[:, None] * e2
    assert peg_shift(cloud, RACK) == pytest.approx(0.02, abs=1e-4)


def test_fixtures_without_a_peg_are_left_alone():
    T = make_pose(random_rotations(1, np.random.default_rng(0))[0], [0.3, 0.1, 0.2])
    np.testing.assert_array_equal(center_on_peg(T, np.random.default_rng(1).normal(size=(200, 3)), fixture("shelf")), T)


@pytest.mark.parametrize("index", [0, 1, 2])
def test_a_mug_hung_off_along_its_hole_is_put_back_on_the_peg(index):
    """The teacher's hang moved 25 mm along e_2: centring on the mug's surface points brings the hole's
    centre back to within 5 mm of the peg's axis, by a move along e_2 only."""
    seed = split("mug", "test")[index]
    mesh, scale = generate("mug", seed), 1.1
    mesh.apply_scale(scale)
    hole = np.array(semantics(mesh).handle_center) * scale
    o, d, e1, e2 = peg_frame(RACK)
    T_rack_obj = make_pose(np.eye(3), 0.025 * e2) @ hang_pose(semantics(mesh), RACK, scale)
    T_base_obj = make_pose(random_rotations(1, np.random.default_rng(index))[0], [0.5, -0.1, 0.1])
    cloud = transform_points(T_base_obj, mesh.sample(4000, seed=index))  # (4000, 3) base frame
    T_seen = T_base_obj @ invert(T_rack_obj)
    out = invert(center_on_peg(T_seen, cloud, RACK)) @ T_base_obj  # the new T_rack_obj

    def side(T):
        return (transform_points(T, hole[None])[0] - o) @ e2

    assert side(T_rack_obj) == pytest.approx(0.025, abs=1e-9)
    assert abs(side(out)) < 0.005
    moved = out @ invert(T_rack_obj)
    np.testing.assert_allclose(moved[:3, :3], np.eye(3), atol=1e-9)
    np.testing.assert_allclose(np.cross(moved[:3, 3], e2), 0.0, atol=1e-9)


def test_the_demos_own_hangs_are_left_within_5_mm():
    """At the place each mug demo really had, its own (single-view) cloud moves the peg by < 5 mm."""
    from app.tasks.demo_library import DEMOS_DIR, task_demos
    from app.tasks.task import task

    shifts = [peg_shift(transform_points(invert(d.place_anchor()), d.cloud), RACK)
              for d in task_demos(DEMOS_DIR / task("mug").demos)]
    assert len(shifts) == 10 and max(abs(s) for s in shifts) < 0.005, shifts
