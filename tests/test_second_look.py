"""Carried grasps and places (round trips), imitation from given starts, the gripper's own points,
the wrist turn of the second look, and the second look's fused cloud of a held mug."""
import numpy as np
import pytest

from app.failures import OutOfJointLimits
from app.jobs.second_look import to_grasp_frame, view_q
from app.nift.imitate import Imitation
from app.predict.carried_grasps import carried_grasps, carried_pairs, carried_places, medoid
from hardware.gripper_geometry import GripperGeometry
from hardware.interfaces import JointLimits
from hardware.se3 import invert, make_pose, random_rotations


def _poses(n, seed):
    rng = np.random.default_rng(seed)
    return np.array([make_pose(R, rng.uniform(-0.3, 0.3, 3)) for R in random_rotations(n, rng)])


def test_a_carried_grasp_holds_the_object_at_its_place_as_the_demo_did():
    places, carried = _poses(3, 0), list(_poses(4, 1))
    G, j_of = carried_grasps(places, carried)
    assert G.shape == (12, 4, 4) and j_of.tolist() == [0] * 4 + [1] * 4 + [2] * 4
    for k, (T, j) in enumerate(zip(G, j_of)):
        assert np.allclose(invert(places[j]) @ T, carried[k % 4], atol=1e-9)  # T_fixture_tcp = demo d's


def test_a_carried_place_puts_the_fixture_where_the_medoid_demo_had_it_for_that_grasp():
    carried = [make_pose(np.eye(3), [x, 0.0, 0.2]) for x in (0.0, 0.01, 0.02, 0.03, 0.3)]
    assert np.allclose(medoid(carried), carried[2])  # nearest the others in sum (0.32 m, the next 0.33 m)
    grasps = _poses(2, 2)
    P = carried_places(grasps, carried)
    for T, place in zip(grasps, P):
        assert np.allclose(invert(place) @ T, carried[2], atol=1e-9)


def test_carried_pairs_score_their_own_grasp_loss_and_keep_one_pose_per_candidate():
    place = Imitation(np.eye(4), np.array([np.eye(4), make_pose(t=[0.2, 0, 0])]), np.array([2.0, 3.0]), 0, 1, 0.0,
                      ranked=np.array([0, 1]))
    grasp = Imitation(np.eye(4), np.array([np.eye(4)]), np.array([1.0]), 0, 1, 0.0, ranked=np.array([0]))
    carried = [make_pose(t=[0.0, 0.0, 0.1]), make_pose(t=[0.001, 0.0, 0.1])]  # one candidate (1 mm apart)
    pairs = carried_pairs(grasp, place, np.eye(4), carried, lambda G: 1.0 + G[:, 0, 3], first_rank=5)
    assert [(c.grasp_rank, c.place_rank) for c in pairs] == [(5, 0), (6, 1)]
    assert pairs[0].score == pytest.approx(0.0) and pairs[1].score == pytest.approx(0.2 + 0.5)
    none = carried_pairs(grasp, place, np.eye(4), carried, lambda G: np.ones(len(G)),
                         feasible=lambda G: np.zeros(len(G), bool))
    assert none == []


def test_the_gripper_contains_points_in_its_palm_and_fingers_only():
    g = GripperGeometry()
    z_finger = g.palm[2] + g.finger[2] / 2 - g.tcp_z  # the fingers' middle, TCP frame
    inside = np.array([[0.0, 0.0, -g.tcp_z + 0.01], [0.0, g.stroke / 2 + g.finger[1] / 2, z_finger]])
    outside = np.array([[0.0, 0.0, z_finger], [0.0, 0.0, 0.05], [0.1, 0.0, -g.tcp_z + 0.01]])
    assert g.contains(inside).all() and not g.contains(outside).any()
    assert g.contains(np.array([[0.0, 0.02, z_finger]]), width=0.03)  # the fingers closed to 3 cm reach it
    assert g.contains(np.array([[0.0, 0.0, z_finger + g.finger[2]]]), margin=0.0).sum() == 0


def test_the_swept_gripper_is_the_union_of_the_gripper_along_its_approach():
    """contains(..., sweep=d) is the box test at every shift s in [0, d] along the tool axis (here on
    a 1 mm grid, which the boxes, 60 mm tall, cannot fall between), on random points near the gripper."""
    g = GripperGeometry()
    points = np.random.default_rng(3).uniform([-0.05, -0.09, -0.2], [0.05, 0.09, 0.05], (4000, 3))
    stepped = np.any([g.contains(points + [0.0, 0.0, s], None, 0.002) for s in np.arange(0.0, 0.1 + 1e-9, 0.001)], axis=0)
    swept = g.contains(points, None, 0.002, sweep=0.1)
    assert stepped.sum() > 500 and (swept == stepped).mean() > 0.999
    assert (g.contains(points, None, 0.002) <= swept).all()  # the gripper at the end of the line is inside its sweep


def test_the_wrist_turns_within_its_limits_and_views_map_back_to_the_grasp():
    limits = JointLimits(np.full(6, -2 * np.pi), np.full(6, 2 * np.pi), np.ones(6), np.ones(6), np.ones(6))
    q = np.array([0.0, -1.0, 1.0, -1.0, -1.5, 5.0])
    assert view_q(q, np.pi, limits)[5] == pytest.approx(5.0 - np.pi)  # +pi would leave the limit
    assert view_q(q * 0, np.pi, limits)[5] == pytest.approx(np.pi)
    with pytest.raises(OutOfJointLimits, match="cannot turn"):
        view_q(q * 0, 13.0, limits)
    T_grasp, T_view = _poses(2, 3)
    points = np.random.default_rng(4).uniform(-0.1, 0.1, (20, 3))
    seen = points @ (T_view @ invert(T_grasp))[:3, :3].T + (T_view @ invert(T_grasp))[:3, 3]  # moved rigidly
    assert np.allclose(to_grasp_frame(seen, T_grasp, T_view), points, atol=1e-9)


@pytest.mark.slow
def test_the_second_look_fuses_a_held_mug_onto_its_mesh_without_the_gripper(monkeypatch):
    """The oracle's grasp holds a mug; the second look's views, in the grasp-time frame, lie on the
    mesh where it stood (95 % of their points within 1 cm, median within 4 mm), show more than the
    first view did, and keep no point inside the gripper's palm or fingers."""
    import trimesh
    from scipy.spatial import cKDTree

    import app.jobs.held_place as job_module
    from app.jobs.job import JobConfig
    from app.motion.scene import PlanningScene
    from app.simcell.cell import CellConfig, SimCell
    from app.simcell.sim_job import JobSpec, SimHooks, oracle_predictor, run_sim_job
    from app.tasks.task import task

    seen = {}

    class Hooks(SimHooks):
        def on_grasped(self) -> None:
            super().on_grasped()
            seen["T_base_obj"], seen["mesh"] = self.cell.world.pose(self.obj.body), self.obj.mesh

    real = job_module.second_look

    def spy(*args, **kwargs):
        seen["views"] = real(*args, **kwargs)
        seen["first"], seen["T_grasp"], seen["width"] = args[4], args[5], args[6]
        return seen["views"]

    monkeypatch.setattr(job_module, "second_look", spy)
    config = CellConfig()
    with SimCell(config) as cell:
        scene = PlanningScene(config)
        try:
            run_sim_job(cell, scene, np.array(cell.camera.config.T_base_cam), JobSpec(task("mug"), seed=1),
                        JobConfig.of("nift", second_look=True), hooks_type=Hooks,
                        predictor_of=lambda obj: oracle_predictor(cell, obj, task("mug")))
        finally:
            scene.close()
    surface = trimesh.sample.sample_surface(seen["mesh"], 30000, seed=0)[0]
    surface = surface @ seen["T_base_obj"][:3, :3].T + seen["T_base_obj"][:3, 3]
    assert len(seen["views"]) == 2  # as the lift left it, and half a turn on
    fused = np.concatenate(seen["views"])
    d = cKDTree(surface).query(fused)[0]
    assert np.percentile(d, 95) < 0.01 and np.median(d) < 0.004, (np.percentile(d, 95), np.median(d))
    beyond_first = cKDTree(seen["first"]).query(fused)[0] > 0.005
    assert beyond_first.sum() > 100
    T = seen["T_grasp"]
    local = (fused - T[:3, 3]) @ T[:3, :3]
    assert GripperGeometry().contains(local, seen["width"]).sum() <= 3
