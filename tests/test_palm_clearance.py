"""Grasps backed off what lies under the palm, and the approach test against the seen points: analytic
back-offs, the cases left alone, and the quick test's answer."""
import numpy as np

from app.jobs.clearance import approach_blocked
from app.motion.ik import Blocked
from app.predict.palm_clearance import backed_off_palm, palm_overlap
from hardware.gripper_geometry import GripperGeometry
from hardware.se3 import make_pose, rotvec_to_matrix

DOWN = rotvec_to_matrix([np.pi, 0.0, 0.0])  # approach axis straight down
FRONT = GripperGeometry().palm[2] - GripperGeometry().tcp_z  # the palm's front face, TCP frame (-0.04 m)


def _cup(rim: float = 0.10, radius: float = 0.04, n: int = 4000) -> np.ndarray:
    """Points of an open cylinder's 3 mm wall, centre (0.5, 0, 0), from the table to `rim`."""
    rng = np.random.default_rng(0)
    a, r, z = rng.uniform(0, 2 * np.pi, n), rng.uniform(radius - 0.0015, radius + 0.0015, n), rng.uniform(0, rim, n)
    return np.column_stack([0.5 + r * np.cos(a), r * np.sin(a), z])


def test_a_grasp_deep_on_a_rim_backs_off_until_the_palm_is_clear_by_the_clearance():
    cup = _cup()
    T = make_pose(DOWN, [0.5, 0.04, 0.10 - 0.048])  # TCP 48 mm down the wall: the palm 8 mm into the rim
    assert np.isclose(palm_overlap(T, cup, 0.0), 0.008, atol=3e-4)
    out = backed_off_palm(T, cup, clearance=0.003)
    np.testing.assert_allclose(out[:3, :3], T[:3, :3])
    assert np.isclose(out[2, 3] - T[2, 3], 0.011, atol=3e-4)  # straight back up its axis: 8 + 3 mm
    assert palm_overlap(out, cup, 0.0) == 0.0 and np.isclose(palm_overlap(out, cup, 0.003), 0.0, atol=1e-9)


def test_grasps_clear_of_the_rim_or_too_deep_are_left_alone():
    cup = _cup()
    shallow = make_pose(DOWN, [0.5, 0.04, 0.10 - 0.02])
    assert np.array_equal(backed_off_palm(shallow, cup), shallow)
    deep = make_pose(DOWN, [0.5, 0.04, 0.10 - 0.08])  # would need 43 mm
    assert np.array_equal(backed_off_palm(deep, cup), deep)


def test_the_quick_test_refuses_a_grasp_whose_way_in_passes_seen_points_and_asks_the_rest():
    cup, asked = _cup(), []

    def reach(T, what):
        asked.append(what)
        return None

    blocked = approach_blocked(reach, cup, 0.10, lambda T: 0.02, GripperGeometry(), arrived=0.007)
    beside = make_pose(DOWN, [0.5, 0.04, 0.10 - 0.03])  # fingers 20 mm apart astride the wall, palm clear
    assert blocked(beside, "grasp") is None and asked == ["grasp"]  # the cell's own test first
    across = make_pose(DOWN @ rotvec_to_matrix([0, 0, np.pi / 2]), [0.5, 0.04, 0.10 - 0.03])  # a finger on the rim
    why = blocked(across, "grasp")
    assert isinstance(why, Blocked) and "seen points" in why.why and asked == ["grasp", "grasp"]
    palm_on_rim = make_pose(DOWN, [0.5, 0.04, 0.10 + FRONT + 0.005])  # palm 5 mm into the rim: within `arrived`
    assert blocked(palm_on_rim, "grasp") is None
    assert blocked(across, "place") is None and asked[-1] == "place"  # only the grasp's way in is its business


def test_a_grasp_moved_away_from_a_slip_goes_no_deeper_than_the_palm_allows(monkeypatch):
    """After a slip, `holding` moves a grasp down its pad plane; a move that puts the palm into the rim
    is not taken, however well the fingers would hold there (the judgement is made to accept all)."""
    import app.jobs.hold as hold
    from app.jobs.hold import holding, object_axis, on_object
    from app.predict.grasp_hold import Hold, HoldConfig
    from app.predict.pairs import Candidate

    monkeypatch.setattr(hold, "judge_hold", lambda *a, **k: Hold(True, reason="held"))
    cup = _cup(rim=0.16)  # tall: its longest axis is its own
    T = make_pose(DOWN, [0.5, 0.04, 0.16 - 0.02])  # palm front 20 mm above the rim
    slip = on_object(T[:3, 3], object_axis(cup))
    c = Candidate(T, np.eye(4), np.eye(4))
    kept, _ = holding([c], cup, None, HoldConfig(slip_away=0.012, moves=(0.01, 0.015)), [slip])
    assert np.isclose(kept[0].T_base_tcp[2, 3], T[2, 3] - 0.015)  # 15 mm down: the palm still 5 mm above
    kept, _ = holding([c], cup, None, HoldConfig(slip_away=0.012, moves=(0.01, 0.03)), [slip])
    assert kept == [c]  # 30 mm down would put the palm 10 mm into the rim: none is moved, all are tried as they are
