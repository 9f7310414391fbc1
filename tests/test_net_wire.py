"""The device network's pieces without a server: the wire format, the argument checks."""

import msgpack
import numpy as np
import pytest

from hardware.interfaces import JointLimits
from hardware.net import checks, wire

LIMITS = JointLimits(-np.full(6, 6.0), np.full(6, 6.0), np.full(6, 3.0), np.full(6, 8.0), np.full(6, 60.0))


@pytest.mark.parametrize("array", [np.arange(6, dtype=np.float64) / 7, np.zeros((424, 512), np.float32),
                                   np.full((4, 5, 3), 7, np.uint8), np.array([True, False]), np.zeros((0, 6))])
def test_arrays_round_trip_bit_for_bit(array):
    back = wire.unpack(wire.pack({"x": array}))["x"]
    assert back.dtype == array.dtype and back.shape == array.shape and np.array_equal(back, array)


def test_a_depth_frame_travels_as_its_bytes_not_a_list():
    depth = np.random.default_rng(0).random((424, 512)).astype(np.float32)
    assert len(wire.pack({"depth": depth})) < depth.nbytes + 100  # a JSON list would be ~10x larger


@pytest.mark.parametrize("payload", [
    b"\x00\x01garbage",  # not msgpack
    msgpack.packb([1, 2, 3]),  # not a map
    msgpack.packb({"x": msgpack.ExtType(9, b"pickle?")}),  # an unknown extension
    msgpack.packb({"x": msgpack.ExtType(wire.ARRAY, msgpack.packb(["|O", [1], b"\x80\x04."]))}),  # object dtype
    msgpack.packb({"x": msgpack.ExtType(wire.ARRAY, msgpack.packb(["<f8", [1000], b"\x00" * 8]))}),  # short data
    b"\xc6" + (wire.MAX_MESSAGE + 10).to_bytes(4, "big"),  # a bin header claiming more than the limit
])
def test_malformed_messages_are_refused_by_name(payload):
    with pytest.raises(wire.WireError):
        wire.unpack(payload)


def test_an_oversized_message_is_refused_before_parsing():
    with pytest.raises(wire.WireError, match="over the"):
        wire.unpack(b"\x00" * (wire.MAX_MESSAGE + 1))


def test_joint_checks_refuse_nan_wrong_shape_and_out_of_limits():
    assert np.array_equal(checks.joints([0.1] * 6, LIMITS), np.full(6, 0.1))
    for bad, why in (([np.nan] * 6, "finite"), ([0.0] * 5, "6 numbers"), ([7.0] * 6, "joint limits"),
                     ("abcdef", "array of numbers"), ([[0.0] * 6], "6 numbers")):
        with pytest.raises(ValueError, match=why):
            checks.joints(bad, LIMITS)


def test_trajectory_checks():
    t, q = np.linspace(0, 1, 5), np.zeros((5, 6))
    assert checks.trajectory(t, q, None, LIMITS)[1].shape == (5, 6)
    with pytest.raises(ValueError, match="increase"):
        checks.trajectory(t[::-1], q, None, LIMITS)
    with pytest.raises(ValueError, match="sample 3"):
        checks.trajectory(t, np.vstack([q[:3], np.full((2, 6), 9.0)]), None, LIMITS)
    with pytest.raises(ValueError, match="velocity"):
        checks.trajectory(t, q, np.full((5, 6), 5.0), LIMITS)


def test_a_trajectory_is_checked_by_the_motion_its_samples_imply_whatever_velocities_it_brings():
    """500 rad/s implied by the positions is refused without velocities, and with zero velocities; a
    Ruckig-timed motion at the limits (sampled at 8 ms) passes, its difference quotients being means."""
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    t, q = np.array([0.0, 0.01]), np.vstack([np.zeros(6), np.full(6, 5.0)])
    for qd in (None, np.zeros((2, 6))):
        with pytest.raises(ValueError, match="moves joint 1 at 500 rad/s"):
            checks.trajectory(t, q, qd, LIMITS)
    with pytest.raises(ValueError, match="accelerates joint 1"):
        checks.trajectory(np.array([0.0, 0.1, 0.2]), np.array([[0.0] * 6, [0.0] * 6, [0.25] * 6]), None, LIMITS)
    inp = InputParameter(6)
    inp.current_position, inp.target_position = [0.0] * 6, [4.0, -3.0, 2.0, 1.0, -5.0, 0.5]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = LIMITS.velocity, LIMITS.acceleration, LIMITS.jerk
    traj = Trajectory(6)
    assert Ruckig(6).calculate(inp, traj) == Result.Working
    times = np.arange(0.0, traj.duration, 0.008)
    samples = [traj.at_time(x) for x in times]
    Q, V = np.array([s[0] for s in samples]), np.array([s[1] for s in samples])
    assert np.abs(V).max() > 0.99 * LIMITS.velocity.min()  # it does reach the limit
    assert checks.trajectory(times, Q, V, LIMITS)[1].shape == Q.shape


def test_poses_beyond_the_workspace_are_refused():
    with pytest.raises(ValueError, match="workspace"):
        checks.pose([441.0, 0, 0, 0, 0, 0])


def test_serve_binds_ipv4_addresses_only():
    from app.commands.serve import check_bind

    check_bind("127.0.0.1")
    check_bind("0.0.0.0")
    with pytest.raises(ValueError, match="IPv4"):
        check_bind("::1")
    with pytest.raises(ValueError, match="not an IP address"):
        check_bind("example.org")
