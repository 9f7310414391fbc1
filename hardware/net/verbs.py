"""Which verbs each device kind answers over the network, what their arguments must be, and how
the server runs them:

    read     answered at once, to any authenticated client (state)
    stop     answered at once, to any authenticated client, also while a motion runs (stopJ)
    command  answered at once, only to the client that commands the device
    motion   runs on the server's motion thread (it moves the device or steps the world), only for
             the commanding client; the reply is a job id, its outcome comes from the "result" verb
    work     like motion, for any client (a capture renders the world, but moves nothing)
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hardware.interfaces import Arm, CameraIntrinsics, DepthCamera, Frame, Gripper, JointLimits
from hardware.net import checks

KINDS = ("read", "stop", "command", "motion", "work")


@dataclass(frozen=True)
class Verb:
    """One verb: `call(device, args)` -> a value for the wire; `kind` (see the module's docstring)."""

    call: Callable[[Any, list], Any]
    kind: str = "read"
    most_args: int = 0

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown verb kind {self.kind!r}; choose one of {', '.join(KINDS)}")


@dataclass(frozen=True)
class Service:
    """A device as the server offers it: its kind ("arm", "gripper", "camera", or another the
    application adds), the object, its verbs, and what discovery advertises about it."""

    kind: str
    device: Any
    verbs: dict[str, Verb]
    properties: dict[str, str] = field(default_factory=dict)
    watchdog: bool = False  # motions stop when the commanding client falls silent
    reset: Callable[[Any], None] | None = None  # back to the settings a new commander expects (on release, handover)
    moves: tuple[str, ...] = ()  # kinds of the other served devices its motions move (a test rig moves the arm):
    # commanding it commands them too, and the watchdog stops them


def arg(args: list, i: int, default: Any = None) -> Any:
    return args[i] if i < len(args) else default


def limits_record(limits: JointLimits) -> dict:
    return {k: getattr(limits, k) for k in ("lower", "upper", "velocity", "acceleration", "jerk")}


def arm_verbs(arm: Arm) -> dict[str, Verb]:
    lim = arm.joint_limits
    speed = lambda v, what, d: checks.number(d if v is None else v, what, 0.0, checks.MAX_SPEED)  # noqa: E731
    accel = lambda v, what, d: checks.number(d if v is None else v, what, 0.0, checks.MAX_ACCELERATION)  # noqa: E731
    return {
        "getActualQ": Verb(lambda a, _: a.getActualQ()),
        "getActualQd": Verb(lambda a, _: a.getActualQd()),
        "getTimestamp": Verb(lambda a, _: a.getTimestamp()),
        "getActualTCPPose": Verb(lambda a, _: a.getActualTCPPose()),
        "getTCPOffset": Verb(lambda a, _: a.getTCPOffset()),
        "isProtectiveStopped": Verb(lambda a, _: a.isProtectiveStopped()),
        "getLastError": Verb(lambda a, _: a.getLastError()),
        "joint_limits": Verb(lambda a, _: limits_record(a.joint_limits)),
        "getForwardKinematics": Verb(lambda a, x: a.getForwardKinematics(
            None if arg(x, 0) is None else checks.joints(x[0], lim)), most_args=1),
        "setTcp": Verb(lambda a, x: a.setTcp(checks.vector(arg(x, 0), 6, "TCP offset")), "command", 1),
        "unlockProtectiveStop": Verb(lambda a, _: a.unlockProtectiveStop(), "command"),
        "getActualTCPForce": Verb(lambda a, _: a.getActualTCPForce()),
        "readContactDetection": Verb(lambda a, _: a.readContactDetection()),
        "startContactDetection": Verb(lambda a, x: a.startContactDetection(
            checks.optional_number(arg(x, 0), "contact detection force", 0.0, checks.MAX_FORCE)), "command", 1),
        "stopContactDetection": Verb(lambda a, _: a.stopContactDetection(), "command"),
        "isTeachMode": Verb(lambda a, _: a.isTeachMode()),
        "teachMode": Verb(lambda a, _: a.teachMode(), "command"),
        "endTeachMode": Verb(lambda a, _: a.endTeachMode(), "command"),
        "stopJ": Verb(lambda a, x: a.stopJ(accel(arg(x, 0), "deceleration", 2.0)), "stop", 1),
        "moveJ": Verb(lambda a, x: a.moveJ(checks.joints(arg(x, 0), lim, "moveJ target"),
                                           speed(arg(x, 1), "speed", 1.05), accel(arg(x, 2), "acceleration", 1.4)),
                      "motion", 3),
        "moveL": Verb(lambda a, x: a.moveL(checks.pose(arg(x, 0), "moveL target"), speed(arg(x, 1), "speed", 0.25),
                                           accel(arg(x, 2), "acceleration", 1.2)), "motion", 3),
        "executeTrajectory": Verb(lambda a, x: a.executeTrajectory(*checks.trajectory(arg(x, 0), arg(x, 1), arg(x, 2), lim)),
                                  "motion", 3),
    }


def gripper_verbs(gripper: Gripper) -> dict[str, Verb]:
    return {
        "stroke": Verb(lambda g, _: g.stroke),
        "max_force": Verb(lambda g, _: g.max_force),
        "width": Verb(lambda g, _: g.width),
        "object_detected": Verb(lambda g, _: g.object_detected),
        "force": Verb(lambda g, _: g.force),
        "open": Verb(lambda g, x: g.open(checks.number(arg(x, 0, 0.1), "speed", 0.0, checks.MAX_SPEED),
                                         checks.optional_number(arg(x, 1), "width", 0.0, g.stroke)), "motion", 2),
        "close": Verb(lambda g, x: g.close(checks.number(arg(x, 0, 40.0), "force", 0.0, g.max_force),
                                           checks.number(arg(x, 1, 0.05), "speed", 0.0, checks.MAX_SPEED)), "motion", 2),
    }


def intrinsics_record(k: CameraIntrinsics) -> dict:
    return {"width": k.width, "height": k.height, "fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy}


def frame_record(f: Frame) -> dict:
    return {"color": np.ascontiguousarray(f.color, np.uint8), "depth": np.ascontiguousarray(f.depth, np.float32),
            "intrinsics": intrinsics_record(f.intrinsics), "timestamp": float(f.timestamp)}


def camera_verbs(camera: DepthCamera) -> dict[str, Verb]:
    last: dict = {}

    def capture(c: DepthCamera) -> dict:
        last["frame"] = frame_record(c.capture())
        return last["frame"]

    def last_frame(c: DepthCamera) -> dict:
        if "frame" not in last:
            raise ValueError("no frame captured yet: call capture first")
        return last["frame"]

    return {"intrinsics": Verb(lambda c, _: intrinsics_record(c.intrinsics)),
            "capture": Verb(lambda c, _: capture(c), "work"),
            "last_frame": Verb(lambda c, _: last_frame(c))}  # the last capture again: what delivery alone costs


def arm_reset(arm: Arm) -> Callable[[Any], None]:
    """What a client's session may have changed on an arm, put back: teach mode ended, contact detection
    off, the TCP offset the server started with."""
    tcp = np.array(arm.getTCPOffset(), float)

    def reset(a: Arm) -> None:
        if a.isTeachMode():
            a.endTeachMode()
        a.stopContactDetection()
        a.setTcp(tcp)

    return reset


def device_service(kind: str, device: Any, properties: dict[str, str] | None = None) -> Service:
    """The service of an arm, gripper or camera."""
    verbs = {"arm": arm_verbs, "gripper": gripper_verbs, "camera": camera_verbs}[kind](device)
    return Service(kind, device, verbs, dict(properties or {}), watchdog=kind == "arm",
                   reset=arm_reset(device) if kind == "arm" else None)
