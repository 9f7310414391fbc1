"""Candidates: distinct poses within a margin of the best (grouping, symmetry, margin), pairs that
carry like the demos, and the candidate set of a demo's own cloud."""
import numpy as np

from app.predict.config import CELL_IMITATION
from app.nift.candidates import (HALF_TURN_Z, CandidateConfig, candidates,
                                 leaders)
from app.nift.imitate import Imitation, imitate
from app.nift.raycast import scene_of
from app.nift.template import build_template
from app.objects import generate
from app.predict.pairs import ranked_pairs
from app.predict.feasibility import grips_something
from app.tasks.anchors import anchor_mesh
from app.tasks.demo_library import DEMOS_DIR, task_demos, task_templates
from app.tasks.task import task
from app.tasks.teacher import grasp_pose
from app.training.views import observe
from hardware.se3 import invert, make_pose, pose_error, rotvec_to_matrix

GRASP = (np.eye(4), HALF_TURN_Z)


def _pose(x=0.0, yaw=0.0, roll=0.0):
    return make_pose(rotvec_to_matrix([roll, 0.0, yaw]), [x, 0.0, 0.0])


def test_a_nearby_pose_and_the_half_turn_are_one_candidate_and_a_far_one_is_another():
    A, near, flipped, far = _pose(), _pose(x=0.005), _pose(yaw=np.pi), _pose(x=0.05)
    poses, losses = np.array([A, near, flipped, far]), np.array([1.0, 1.01, 1.02, 1.03])
    lead, follow = leaders(poses, losses, CandidateConfig(), GRASP)
    assert lead.tolist() == [0, 3] and sorted(follow.tolist()) == [1, 2]
    lead, _ = leaders(poses, losses, CandidateConfig())  # without the symmetry the half-turn is its own
    assert lead.tolist() == [0, 2, 3]


def test_candidates_keep_the_distinct_poses_within_the_margin_best_first_and_respect_allowed():
    poses = np.array([_pose(x=0.1 * k) for k in range(4)])
    losses = np.array([1.2, 1.0, 1.1, 2.0])
    assert candidates(poses, losses, CandidateConfig(margin=0.15)).tolist() == [1, 2]
    assert candidates(poses, losses, CandidateConfig(margin=0.25)).tolist() == [1, 2, 0]
    assert candidates(poses, losses, CandidateConfig(margin=0.25, most=1)).tolist() == [1]
    allowed = np.array([True, False, False, True])
    assert candidates(poses, losses, CandidateConfig(margin=1.0), allowed=allowed).tolist() == [0, 3]
    assert candidates(poses, losses, CandidateConfig(), allowed=np.zeros(4, bool)).tolist() == [1, 2]  # none: all


def _imitation(poses, losses):
    poses, losses = np.array(poses), np.array(losses, float)
    return Imitation(poses[0], poses, losses, 0, 0, 0.0, None, np.arange(len(poses)))


def test_pairs_are_ranked_by_summed_relative_excess_and_a_place_turning_the_object_over_is_left_out():
    T_fixture = make_pose(t=[0.5, 0.4, 0.0])
    G0, G1 = make_pose(t=[0.5, 0.0, 0.10]), make_pose(t=[0.52, 0.0, 0.10])
    P0 = make_pose(t=[0.5, 0.0, -0.05])  # the fixture seen 15 cm below the grasp, as in the demo
    P_over = P0 @ make_pose(rotvec_to_matrix([np.pi, 0.0, 0.0]))  # turned over: the grasp would sit below it
    carried = [invert(P0) @ G0]  # the demo's T_fixture_tcp
    pairs = ranked_pairs(_imitation([G0, G1], [10.0, 11.0]), _imitation([P0, P_over], [5.0, 5.1]), T_fixture, carried)
    assert [(c.grasp_rank, c.place_rank) for c in pairs] == [(0, 0), (1, 0)]
    assert np.isclose(pairs[1].score, 0.1)
    assert np.allclose(pairs[0].T_base_tcp_place, T_fixture @ invert(P0) @ G0)
    everything = ranked_pairs(_imitation([G0, G1], [10.0, 11.0]), _imitation([P0, P_over], [5.0, 5.1]), T_fixture)
    assert len(everything) == 4 and np.isclose(everything[1].score, 0.02)


def test_on_a_bowls_own_cloud_the_best_candidate_is_its_grasp():
    mesh = generate("bowl", 2)
    center = mesh.bounds.mean(axis=0)
    radius = float(np.linalg.norm(mesh.vertices - center, axis=1).max())
    T_base_obj = make_pose(rotvec_to_matrix([0, 0, 0.3]), [0.5, 0.0, 0.0])
    cloud = observe(scene_of(mesh), "single", np.eye(3), center, radius, 1024, np.random.default_rng(2))
    cloud = cloud @ T_base_obj[:3, :3].T + T_base_obj[:3, 3]
    truth = T_base_obj @ grasp_pose(mesh)
    template = build_template("gripper", anchor_mesh("gripper"), [{"cloud": cloud, "T_frame_anchor": truth}])
    best = imitate(template, cloud, CELL_IMITATION).candidates[0]
    d, a = min((pose_error(best @ S, truth) for S in GRASP), key=lambda e: e[0])
    assert d <= 0.005 and np.degrees(a) <= 5.0, (d, np.degrees(a))


def test_on_a_demo_cloud_the_shipped_bowl_template_gives_several_distinct_rim_grasps():
    """A body of revolution: rim points all round imitate the ten demos' mean about equally well."""
    t = task("bowl")
    directory = DEMOS_DIR / t.demos
    cloud = task_demos(directory)[3].cloud
    template = task_templates(t, directory)["grasp"]
    result = imitate(template, cloud, CELL_IMITATION, feasible=grips_something(cloud))
    found = result.candidates
    assert len(found) >= 2, result.candidate_losses
    _, follow = leaders(found, result.candidate_losses, CELL_IMITATION.candidates, GRASP)
    assert len(follow) == 0  # distinct
    assert np.all(result.candidate_losses <= result.candidate_losses[0] * (1 + CELL_IMITATION.candidates.margin))
