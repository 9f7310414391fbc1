"""The grasp-hold check: a cap that narrows to the top is ruled out, the body accepted, and the
simulator agrees (the ruled-out grasp slips in a lift, the accepted one survives it); after a slip
the next grasp keeps its distance."""
from __future__ import annotations

import numpy as np
import pytest

from app.jobs.hold import distance_on_object, holding, object_axis, on_object
from app.objects import bottle
from app.objects.catalog import _rng
from app.predict.grasp_hold import HoldConfig, judge_hold, moved_down
from app.predict.pairs import Candidate
from hardware.se3 import make_pose, transform_points

SIDE = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]).T  # x up, closing along x, approach +y
EYE = np.array([-1.0, 0.0, 0.3])  # the camera on the -x side, as the cell's Kinect sees the object
SEED = 200_010
STEEP = {"cap_taper_deg": 30.0, "cap_radius": 0.013, "cap_height": 0.025}


def tapered_bottle(fixed: dict = STEEP):
    """A round-bodied bottle with a tall cap that narrows to the top, no lip; its semantics."""
    mesh, sem = bottle.build(SEED, _rng("bottle", SEED), "tapered-cap", fixed)
    mesh.metadata.update(semantics=sem, name="tapered-test")
    return mesh, sem


def heights(sem) -> dict[str, float]:
    return {"cap": sem.neck_range[1] + 0.4 * (sem.height - sem.neck_range[1]),
            "body": sem.params["body_height"] * 0.5}


def seen_cloud(mesh, T_world_obj=np.eye(4), noise=0.0007) -> np.ndarray:
    """The half of the surface the camera on -x sees, with depth noise, in the world frame."""
    points = mesh.sample(20000, seed=0)
    points = points[points[:, 0] < 0.002]
    points = points + np.random.default_rng(0).normal(scale=noise, size=points.shape)
    return transform_points(T_world_obj, points)


def test_a_cap_that_narrows_to_the_top_is_ruled_out_and_the_body_accepted():
    mesh, sem = tapered_bottle()
    cloud = seen_cloud(mesh)
    z = heights(sem)
    cap = judge_hold(make_pose(SIDE, [0, 0, z["cap"]]), cloud, eye=EYE)
    body = judge_hold(make_pose(SIDE, [0, 0, z["body"]]), cloud, eye=EYE)
    assert cap.holds is False and "narrows towards the top" in cap.reason and cap.taper_deg > 15
    assert body.holds is True and abs(body.taper_deg) < 5


def test_a_straight_cap_and_a_lipped_neck_are_accepted():
    mesh, sem = tapered_bottle({"cap_taper_deg": 0.0})
    cap = judge_hold(make_pose(SIDE, [0, 0, heights(sem)["cap"]]), seen_cloud(mesh), eye=EYE)
    assert cap.holds is True and abs(cap.taper_deg) < 5


def test_the_judgement_turns_with_the_object():
    """A cap tapering by 20 deg lying on its side, gripped from above: gravity no longer runs along the
    taper (no slide-out), and the contact normals stay within the friction cone; standing, it slides out."""
    mesh, sem = tapered_bottle({**STEEP, "cap_taper_deg": 20.0})
    lying = make_pose(np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]]), [0, 0, 0.05])  # its axis along world -y
    at = lying @ np.append([0, 0, heights(sem)["cap"]], 1.0)
    from_above = make_pose(np.array([[0, 1.0, 0], [1.0, 0, 0], [0, 0, -1.0]]), at[:3])  # closing along world x
    held = judge_hold(from_above, transform_points(lying, mesh.sample(20000, seed=0)), eye=at[:3] + [0, 0, 1.0])
    assert held.holds is True and abs(held.taper_deg) < 5, held.reason
    standing = judge_hold(make_pose(SIDE, [0, 0, heights(sem)["cap"]]), seen_cloud(mesh), eye=EYE)
    assert standing.holds is False


def test_a_grasp_that_would_slide_out_is_moved_down_to_one_that_holds():
    mesh, sem = tapered_bottle()
    T = make_pose(SIDE, [0, 0, heights(sem)["cap"]])
    assert np.allclose(moved_down(T, 0.02)[:3, 3], T[:3, 3] - [0, 0, 0.02])
    c = Candidate(T, np.eye(4), np.eye(4))
    kept, ruled = holding([c], seen_cloud(mesh), EYE, HoldConfig(moves=(0.01, 0.02, 0.03, 0.04, 0.05)), [])
    assert len(kept) == 1 and kept[0].T_base_tcp[2, 3] < T[2, 3] - 0.005 and not ruled
    kept, ruled = holding([c], seen_cloud(mesh), EYE, HoldConfig(moves=()), [])
    assert kept == [c] and ruled == [], "every grasp ruled out: the cell still tries the best one"


def test_after_a_slip_the_next_grasp_is_at_least_the_stated_distance_away():
    mesh, sem = tapered_bottle()
    z = heights(sem)
    grasps = [make_pose(SIDE, [0, 0, h]) for h in (z["cap"], z["cap"] - 0.01, z["body"])]
    slipped = on_object(grasps[0][:3, 3], object_axis(seen_cloud(mesh)))
    # the bottle fell over and turned: its cloud and the slipped position are compared in its own axes
    fallen = make_pose(np.array([[0, 0, 1.0], [0, 1.0, 0], [-1.0, 0, 0]]), [0.3, 0.1, 0.04])
    cloud = transform_points(fallen, mesh.sample(20000, seed=1))
    options = [Candidate(fallen @ T, np.eye(4), np.eye(4), grasp_rank=k) for k, T in enumerate(grasps)]
    for moves in ((), HoldConfig().moves):
        config = HoldConfig(slip_away=0.03, moves=moves)
        kept, ruled = holding(options, cloud, None, config, [slipped])
        assert 2 in [c.grasp_rank for c in kept] and all("slipped" in r["outcome"] for r in ruled)
        assert len(kept) + len(ruled) == 3 and (ruled or moves), "without moves the cap grasps are ruled out"
        for c in kept:
            assert distance_on_object(on_object(c.T_base_tcp[:3, 3], object_axis(cloud)), slipped) >= config.slip_away


@pytest.mark.slow
def test_in_the_simulator_the_ruled_out_grasp_slips_and_the_accepted_one_holds(tmp_path):
    from app.objects.collision import collision_model
    from app.objects.library import LibraryObject
    from app.simcell.judges import judge_grasp
    from app.simcell.spawn import spawn
    from hardware.sim.world import SimWorld, SimWorldConfig

    mesh, sem = tapered_bottle()
    source = LibraryObject("tapered-test", "bottle", mesh, collision_model(mesh), {})
    world = SimWorld(SimWorldConfig())
    world.connect()
    try:
        verdicts = {}
        for name, z in heights(sem).items():
            obj = spawn(world, "bottle", 0, "upright", T_world_obj=make_pose(np.eye(3), [0.5, 0.0, 0.0]), source=source)
            T_world_obj = world.pose(obj.body)
            T = T_world_obj @ make_pose(SIDE, [0, 0, z])
            judged = judge_hold(T, seen_cloud(mesh, T_world_obj), eye=T_world_obj[:3, 3] + EYE)
            verdicts[name] = (judged.holds, judge_grasp(world, obj, T).success)
            world.remove(obj.body)
    finally:
        world.disconnect()
    assert verdicts == {"cap": (False, False), "body": (True, True)}, verdicts


def test_a_rim_grasp_holds_a_wall_flat_and_is_not_judged():
    """The teacher's rim grasp of a mug closes on the wall alone (not the far wall across the cavity)."""
    from app.objects import generate
    from app.tasks.teacher import grasp_pose

    mug = generate("mug", 100_000)
    held = judge_hold(grasp_pose(mug), mug.sample(20000, seed=0))
    assert held.holds is None and "a wall" in held.reason


def test_a_grasp_above_the_top_closes_on_nothing_and_is_moved_down_onto_the_cap():
    """A taller object than the demos': the imitated grasp's pads end above its top. Nothing lies between
    them and all beside them lies below: ruled out, and the move down lands on the (straight) cap."""
    mesh, sem = tapered_bottle({"cap_taper_deg": 0.0})
    T = make_pose(SIDE, [0, 0, sem.height + 0.015])  # pads 22 mm wide: their lower edge 4 mm above the top
    judged = judge_hold(T, seen_cloud(mesh), eye=EYE)
    assert judged.holds is False and "close on nothing" in judged.reason
    kept, ruled = holding([Candidate(T, np.eye(4), np.eye(4))], seen_cloud(mesh), EYE, HoldConfig(), [])
    assert len(kept) == 1 and not ruled
    assert sem.neck_range[1] < kept[0].T_base_tcp[2, 3] < sem.height, "moved down onto the cap"


def test_a_rim_grasp_whose_rim_is_hidden_is_not_called_empty():
    """The surface under a rim grasp hidden from the camera: the rim beside the fingers shows at their height,
    so the grasp is left unjudged, not ruled out."""
    from app.objects import generate
    from app.predict.grasp_centering import swept_mask
    from app.tasks.teacher import grasp_pose

    mug = generate("mug", 100_000)
    T = grasp_pose(mug)
    cloud = mug.sample(20000, seed=0)
    cloud = cloud[~swept_mask(T, cloud)]  # nothing between the fingers seen
    held = judge_hold(T, cloud)
    assert held.holds is None, held.reason


def test_a_grasp_on_a_cap_s_top_edge_is_ruled_out_and_moved_down_onto_more_of_it():
    """The pads' lower edge 2 mm below a straight cap's top: they would hold its top edge alone (less than
    `min_grip_height`); 10 mm lower they hold 12 mm of it, and that holds."""
    mesh, sem = tapered_bottle({"cap_taper_deg": 0.0})
    T = make_pose(SIDE, [0, 0, sem.height + 0.009])  # the pads span 22 mm across the height
    judged = judge_hold(T, seen_cloud(mesh), eye=EYE)
    assert judged.holds is False and "only the top" in judged.reason, judged.reason  # 2 mm, and the depth noise
    kept, ruled = holding([Candidate(T, np.eye(4), np.eye(4))], seen_cloud(mesh), EYE, HoldConfig(), [])
    assert len(kept) == 1 and not ruled and np.isclose(kept[0].T_base_tcp[2, 3], T[2, 3] - 0.01)
