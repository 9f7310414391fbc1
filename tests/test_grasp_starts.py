"""Grasp starts from the demos as gravity sees them (`app.predict.grasp_starts`)."""
from types import SimpleNamespace

import numpy as np

from app.predict.grasp_starts import gravity_starts, top_centre
from hardware.se3 import make_pose, random_rotations, rotvec_to_matrix


def _demos(rng: np.random.Generator, n: int = 3) -> list[SimpleNamespace]:
    return [SimpleNamespace(cloud=rng.normal(size=(200, 3)) * 0.05 + rng.uniform(-0.3, 0.3, 3),
                            T_base_tcp=make_pose(random_rotations(1, rng)[0], rng.uniform(-0.3, 0.3, 3)))
            for _ in range(n)]


def test_a_demos_own_cloud_starts_at_its_own_grasp() -> None:
    rng = np.random.default_rng(0)
    demos = _demos(rng)
    for d, demo in enumerate(demos):
        S = gravity_starts(demos, demo.cloud, 4)
        assert S.shape == (12, 4, 4)
        np.testing.assert_allclose(S[4 * d], demo.T_base_tcp, atol=1e-12)  # turn 0 of its own demo


def test_starts_move_with_the_cloud_and_turn_about_its_top_centre() -> None:
    rng = np.random.default_rng(1)
    demos = _demos(rng)
    cloud = rng.normal(size=(300, 3)) * 0.04 + np.array([0.5, 0.1, 0.05])
    S = gravity_starts(demos, cloud, 4)
    shift = np.array([0.1, -0.2, 0.03])
    moved = gravity_starts(demos, cloud + shift, 4)
    np.testing.assert_allclose(moved[:, :3, :3], S[:, :3, :3], atol=1e-12)
    np.testing.assert_allclose(moved[:, :3, 3], S[:, :3, 3] + shift, atol=1e-12)
    a = top_centre(cloud)
    about_a = make_pose(np.eye(3), a) @ make_pose(rotvec_to_matrix([0.0, 0.0, np.pi / 2])) @ make_pose(np.eye(3), -a)
    np.testing.assert_allclose(S[1], about_a @ S[0], atol=1e-12)  # the next turn: a quarter turn about the vertical
    assert not np.allclose(S[1], S[0])


def test_no_turns_no_starts() -> None:
    rng = np.random.default_rng(2)
    assert gravity_starts(_demos(rng), rng.normal(size=(50, 3)), 0).shape == (0, 4, 4)
