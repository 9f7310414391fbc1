"""Fake devices: the `Arm`, `Gripper` and `DepthCamera` interfaces over a kinematic world, with no
physics and no simulator, scripted by tests (a motion that stops, a grasp that slips, a release that
jams). They answer in milliseconds, so a job's every branch can be unit-tested (`tests/test_job_branches.py`)."""
from hardware.fake.arm import FakeArm, FakeArmConfig, Interruption, Motion
from hardware.fake.camera import FakeCamera, FakeCameraConfig
from hardware.fake.gripper import FakeGripper, FakeGripperConfig
from hardware.fake.world import FakeObject, FakeWorld

__all__ = ["FakeArm", "FakeArmConfig", "FakeCamera", "FakeCameraConfig", "FakeGripper", "FakeGripperConfig",
           "FakeObject", "FakeWorld", "Interruption", "Motion"]
