"""Will a grasp hold? Judged from the cell's own cloud before the grasp is chosen (our addition).

A parallel gripper holds by friction at its two pad contacts. In the TCP frame (x along the finger
width, y the closing axis, z the approach) the pads meet the outermost surface on each side of what
lies between them. For each side s = +1, -1 take the swept points (`grasp_centering.swept_points`);
along each of the pad's axes (x, z) bin them, keep per bin the outermost s*y (the ridge the pad
meets first) and fit a line to the bins within `patch_depth` of the outermost, giving the slopes
b_x, b_z of the surface under the pad:

    outward normal  n_s = (-b_x, s, -b_z) / |(-b_x, s, -b_z)|

Two tests, each from Coulomb friction with coefficient mu between pad and object:

- antipodal: each contact normal lies within the friction cone about the closing axis,
      angle(n_s, s*y) = atan(sqrt(b_x^2 + b_z^2)) <= atan(mu);
- taper: with u the direction against gravity projected into the pad plane (unit; skipped when
  gravity runs along the closing axis), the surface under a pad that narrows towards the top tilts
  its normal upwards by beta = asin(n_s . u); the squeeze then pushes the object down, out of the
  fingers, and gravity helps it: the grasp slides out when the wedge's half-angle, beta averaged over
  the sides seen, exceeds `max_taper_deg` (a cap that narrows towards the top and has no lip). Coulomb
  alone would allow nearly atan(mu); the limit is lower because a flat pad meets a taper along one
  line at its lower edge, which resists no turn of a tall object in the lift and the carry: the limit
  is measured in the simulated cell (docs/grasp-hold.md). A grip thinner than `min_width` (a rim's
  wall) is not a wedge and is not judged for taper.

Too few points to judge leaves the grasp unjudged (`holds` None): a single view often hides one side.
Nothing seen between the fingers, with all that lies beside them (along the finger width) below
them, is judged not to hold: the fingers would close on nothing (a grasp imitated above a taller
object's top); so is material that reaches less than `min_grip_height` above the pads' lower edge
(the top edge of a cap). Moved down (`app.jobs.hold`), either may hold.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.predict.grasp_centering import nearest_layer, swept_mask, swept_points
from hardware.gripper_geometry import GripperGeometry

UP = np.array([0.0, 0.0, 1.0])  # against gravity, in the base frame
RIDGE_BINS = 3  # the ridge's slope is fitted over at least this many bins


@dataclass(frozen=True)
class HoldConfig:
    """How a grasp's hold is judged."""

    check: bool = True  # judge grasps before the plan (false: every grasp is tried as imitation ranks it)
    friction: float = 0.6  # pad-object Coulomb coefficient assumed (rubber pads on plastic or glass)
    max_taper_deg: float = 15.0  # a steeper narrowing towards the top slides out: in the simulated cell caps
    # judged at 21-31 deg slipped in a lift, none judged at 13 deg (docs/grasp-hold.md)
    cell: float = 0.003  # m: bins along each of the pad's axes
    patch_depth: float = 0.004  # m: bins of the ridge this close to the outermost one are the pad's patch
    min_cells: int = 4  # fewer points on a side: that side is not judged
    seen_side: float = -0.3  # a side whose pad faces away from the camera beyond this cosine is hidden
    min_width: float = 0.012  # m: a thinner grip (a rim's wall) is held flat between the pads and not judged
    moves: tuple[float, ...] = (0.01, 0.02, 0.03, 0.04, 0.05)  # m: a grasp that would slide out, or lies near
    # one that slipped, is tried this far down its pad plane
    slip_away: float = 0.03  # m: after a slip, grasps this close to the slipped one are not tried again
    min_gravity: float = 0.3  # |u| below this: gravity runs along the closing axis, no taper to judge
    min_grip_height: float = 0.008  # m: the material between the pads must reach this far above their lower edge
    # (against gravity): less, and the fingers hold only the top of the object - a cap's top edge
    beside: float = 0.025  # m: nothing seen between the fingers, and what lies this far beside their middle
    # (along the finger width) all below them: the fingers would close above the object's top


@dataclass(frozen=True)
class Hold:
    """The judgement of one grasp: holds (None: not judged), the worst contact's tilts, and why."""

    holds: bool | None
    taper_deg: float | None = None  # the larger beta of the two sides
    cone_deg: float | None = None  # the larger angle of a contact normal from the closing axis
    reason: str = ""


def ridge_slope(along: np.ndarray, out: np.ndarray, config: HoldConfig) -> float | None:
    """Slope d(out)/d(along) of the ridge - the outermost point per `cell`-wide bin of `along` - over the
    bins within `patch_depth` of the outermost; None when fewer than two bins are there."""
    bins = np.floor(along / config.cell).astype(int)  # (K,)
    keys, which = np.unique(bins, return_inverse=True)
    top = np.full(len(keys), -np.inf)
    np.maximum.at(top, which.ravel(), out)  # (B,) the ridge
    patch = top >= top.max() - config.patch_depth
    if patch.sum() < RIDGE_BINS:  # a contact at the pad's edge on a surface that keeps widening beyond it:
        order = np.argsort(np.abs(np.arange(len(keys)) - int(np.argmax(top))), kind="stable")
        patch = np.zeros(len(keys), bool)
        patch[order[:RIDGE_BINS]] = True  # the bins next to the outermost one show how steeply it widens
    if patch.sum() < 2:
        return None
    return float(np.polyfit((keys[patch] + 0.5) * config.cell, top[patch], 1)[0])


def side_normal(points: np.ndarray, side: int, config: HoldConfig) -> np.ndarray | None:
    """Outward normal (3,), TCP frame, of the patch the pad on `side` (+1: +y, -1: -y) presses on, from
    the slopes of the surface's outermost ridge along the pad's two axes (x, z); None when too few
    points show it."""
    if len(points) < config.min_cells:
        return None
    out = side * points[:, 1]  # (K,) how far out towards the pad
    bx, bz = (ridge_slope(points[:, k], out, config) for k in (0, 2))
    if bx is None and bz is None:
        return None
    n = np.array([-(bx or 0.0), side, -(bz or 0.0)])
    return n / np.linalg.norm(n)


def judge_hold(T_base_tcp: np.ndarray, cloud: np.ndarray, config: HoldConfig = HoldConfig(),
               geometry: GripperGeometry = GripperGeometry(), up: np.ndarray = UP,
               eye: np.ndarray | None = None) -> Hold:
    """Whether the grasp at T_base_tcp (4, 4) will hold what the cloud (N, 3, base frame) shows between
    the fingers (see the module's docstring); `eye`: the camera's position (3,), whose view shows only
    the side of the object facing it (a side whose pad faces away is not judged)."""
    p = swept_points(T_base_tcp, cloud, geometry)  # (K, 3) TCP frame
    if len(p) < config.min_cells and above_the_top(T_base_tcp, cloud, config, geometry, up):
        return Hold(False, reason="nothing between the fingers and the object's top below them: "
                                  "they would close on nothing")
    if len(p) < 2 * config.min_cells:
        return Hold(None, reason="too few points between the fingers to judge the hold")
    p = p[nearest_layer(p[:, 1])]  # what the fingers close on: a mug's far wall across its cavity is not held
    if np.ptp(p[:, 1]) < config.min_width:
        return Hold(None, reason=f"a grip {1000 * np.ptp(p[:, 1]):.0f} mm thick (a wall): held flat, not judged")
    height = grip_height(p, T_base_tcp, config, geometry, up)
    if height is not None and height < config.min_grip_height:
        return Hold(False, reason=f"the fingers would hold only the top {1000 * max(height, 0.0):.0f} mm of it "
                                  f"(at least {1000 * config.min_grip_height:.0f}): it would slide out")
    middle = (p[:, 1].min() + p[:, 1].max()) / 2
    sides = (1, -1)
    if eye is not None:
        view = T_base_tcp[:3, :3].T @ (np.asarray(eye, float) - T_base_tcp[:3, 3])  # (3,) TCP frame
        sides = tuple(s for s in sides if s * view[1] / np.linalg.norm(view) >= config.seen_side)
    normals = {s: side_normal(p[s * (p[:, 1] - middle) > 0], s, config) for s in sides}
    normals = {s: n for s, n in normals.items() if n is not None}
    if not normals:
        return Hold(None, reason="no pad's contact patch is seen well enough to judge the hold")
    u = pad_up(T_base_tcp, config, up)
    cone = max(np.degrees(np.arccos(min(1.0, abs(n[1])))) for n in normals.values())
    tilts = [np.degrees(np.arcsin(np.clip(n @ u, -1, 1))) for n in normals.values()] if u is not None else [0.0]
    taper = float(np.mean(tilts))
    limit = np.degrees(np.arctan(config.friction))
    if cone > limit:
        return Hold(False, taper, cone, f"the pads' contacts are not antipodal: a contact normal is {cone:.0f} deg "
                                        f"off the closing axis, outside the {limit:.0f} deg friction cone")
    if taper > config.max_taper_deg:
        return Hold(False, taper, cone, f"the surface under the pads narrows towards the top by {taper:.0f} deg "
                                        f"(more than {config.max_taper_deg:.0f}): it would slide out of the fingers")
    return Hold(True, taper, cone, "holds: antipodal contacts, no taper that slides out")


def grip_height(p: np.ndarray, T_base_tcp: np.ndarray, config: HoldConfig,
                geometry: GripperGeometry = GripperGeometry(), up: np.ndarray = UP) -> float | None:
    """How far (m) the material between the pads (`p`, (K, 3) TCP frame) reaches above the pads' lowest
    point, against gravity: max_k p_k . u - min_pad c . u over the pad's corners c; None when gravity runs
    along the closing axis."""
    u = pad_up(T_base_tcp, config, up)
    if u is None:
        return None
    z0 = geometry.palm[2] - geometry.tcp_z  # the pad from the palm (z0) to the fingertips (z1), TCP frame
    z1 = z0 + geometry.finger[2]
    lowest = -geometry.finger[0] / 2 * abs(u[0]) + min(z0 * u[2], z1 * u[2])
    return float((p @ u).max() - lowest)


def above_the_top(T_base_tcp: np.ndarray, cloud: np.ndarray, config: HoldConfig,
                   geometry: GripperGeometry = GripperGeometry(), up: np.ndarray = UP) -> bool:
    """Whether what the cloud shows within `beside` of the fingers' middle (along the finger width) lies
    all below the TCP, gravity running in the pad plane: a grasp above the object's top. (Where the
    surface under a rim grasp is hidden from the camera, the rim beside it shows at the fingers'
    height, and this is False.)"""
    u = pad_up(T_base_tcp, config, up)
    if u is None:
        return False
    near = np.asarray(cloud, float).reshape(-1, 3)[swept_mask(T_base_tcp, cloud, geometry, config.beside)]
    if len(near) < config.min_cells:
        return False
    heights = (near - T_base_tcp[:3, 3]) @ (T_base_tcp[:3, :3] @ u)  # (K,) m along up
    return bool(np.all(heights < 0.0))


def pad_up(T_base_tcp: np.ndarray, config: HoldConfig, up: np.ndarray = UP) -> np.ndarray | None:
    """(3,) the unit direction against gravity in the pad plane, TCP frame; None when gravity runs along the
    closing axis (`min_gravity`): then there is no up or down on the pads."""
    u = up_in_pad_plane(T_base_tcp, up)
    norm = np.linalg.norm(u)
    return None if norm < config.min_gravity else u / norm


def up_in_pad_plane(T_base_tcp: np.ndarray, up: np.ndarray = UP) -> np.ndarray:
    """(3,) the direction against gravity in the TCP frame, less its part along the closing axis (y)."""
    u = T_base_tcp[:3, :3].T @ up
    u[1] = 0.0
    return u


def moved_down(T_base_tcp: np.ndarray, distance: float, up: np.ndarray = UP) -> np.ndarray:
    """The grasp moved `distance` m along gravity within its pad plane (its orientation kept): away from
    a cap that narrows towards the top, towards the neck or the body under it."""
    u = up_in_pad_plane(T_base_tcp, up)
    if np.linalg.norm(u) < 1e-9:
        return T_base_tcp.copy()
    out = T_base_tcp.copy()
    out[:3, 3] -= distance * (T_base_tcp[:3, :3] @ (u / np.linalg.norm(u)))
    return out
