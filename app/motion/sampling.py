"""Joint-space sampling-based planning: OMPL's RRTConnect against the planning scene.

A transit whose direct joint path collides is planned by RRT-Connect (Kuffner and LaValle 2000) in
a box of the UR5's joint space around its two ends: every state is checked with
`PlanningScene.collisions` (robot, gripper, table, fixtures, the observed object's hull and, while
it is held, the carried object), edges every `resolution` radians. OMPL's path simplifier then
shortcuts the path. It is returned as waypoints (K, 6); the caller times it and checks the timed
motion again, where `densify` helps when a timed segment strays from its straight joint line.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from app.failures import NoPath
from app.motion.scene import PlanningScene

JOINT_BOUND = 2 * np.pi  # rad: every UR5 joint turns +-360 degrees


@dataclass(frozen=True)
class SamplingConfig:
    """How the sampling planner searches."""

    states: int = 20_000  # states checked per transit before giving up: a budget of work, not of time, so that a
    # job is a function of its seed however busy the machine is (about 2 s at 0.1 ms a state; 3.5 s constrained)
    timeout: float = 10.0  # s: a cap in time as well, far above what `states` take
    margin: float = np.pi  # rad: the search box extends this far beyond both ends, per joint
    resolution: float = 0.02  # rad of joint motion between checked states on an edge
    max_step: float = 0.4  # rad: the longest edge RRT-Connect grows at once
    seed: int = 1  # OMPL's random seed: the same problem gives the same path


def _ompl():
    """OMPL's modules, quiet (its log goes to stdout otherwise)."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LOG_NONE)
    return ob, og, ou


def plan_joint_path(scene: PlanningScene, q0: np.ndarray, q1: np.ndarray, ignore: tuple[str, ...] = (),
                    config: SamplingConfig = SamplingConfig(),
                    allowed: Callable[[np.ndarray], bool] | None = None) -> np.ndarray:
    """Collision-free joint waypoints (K, 6) from q0 to q1, both included, or NoPath - at once when an
    end collides (RRT-Connect would sample towards an invalid goal until its time is up). `allowed`:
    a path constraint every state must meet too (MoveIt's path constraints, checked by rejection)."""
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    for end, q in (("start", q0), ("goal", q1)):
        hits = scene.collisions(q, ignore)
        if hits:
            raise NoPath(f"the transit's {end} collides ({', '.join(hits[:3])})")
    ob, og, ou = _ompl()
    ou.RNG.setSeed(config.seed)
    dof = len(q0)
    space = ob.RealVectorStateSpace(dof)
    bounds = ob.RealVectorBounds(dof)
    low, high = search_box(q0, q1, config.margin)
    for j in range(dof):
        bounds.setLow(j, float(low[j]))
        bounds.setHigh(j, float(high[j]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    checked = 0

    def valid(state) -> bool:
        nonlocal checked
        checked += 1
        q = _array(state, dof)
        return bool((allowed is None or allowed(q)) and scene.is_free(q, ignore))  # the cheap test first

    setup.setStateValidityChecker(valid)
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(config.resolution / space.getMaximumExtent())
    planner = og.RRTConnect(info)
    planner.setRange(config.max_step)
    setup.setPlanner(planner)
    start, goal = space.allocState(), space.allocState()
    for j in range(dof):
        start[j], goal[j] = float(q0[j]), float(q1[j])
    setup.setStartAndGoalStates(start, goal)
    budget = ob.plannerOrTerminationCondition(ob.PlannerTerminationCondition(lambda: checked >= config.states),
                                              ob.timedPlannerTerminationCondition(config.timeout))
    try:
        solved = setup.solve(budget) and setup.haveExactSolutionPath()
        if not solved:
            what = "collision-free" if allowed is None else "collision-free, constrained"
            raise NoPath(f"no {what} joint path within {config.states} states of RRT-Connect")
        path = setup.getSolutionPath()
        simplifier = setup.getPathSimplifier()
        simplifier.reduceVertices(path)  # shortcut between random pairs of vertices
        simplifier.ropeShortcutPath(path)
        waypoints = np.array([_array(path.getState(i), dof) for i in range(path.getStateCount())])  # (K, 6)
    finally:
        del setup, planner, info, start, goal, space, bounds, budget  # OMPL's objects go now, not at exit
    waypoints[0], waypoints[-1] = q0, q1
    return waypoints


def search_box(q0: np.ndarray, q1: np.ndarray, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) joint bounds (D,) of the search: `margin` beyond both ends, within the joints' range."""
    return (np.maximum(np.minimum(q0, q1) - margin, -JOINT_BOUND),
            np.minimum(np.maximum(q0, q1) + margin, JOINT_BOUND))


def densify(waypoints: np.ndarray, max_step: float) -> np.ndarray:
    """The same path (K, D) with straight joint-space points inserted so no edge moves a joint more
    than max_step."""
    out = [waypoints[0]]
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        n = max(1, int(np.ceil(np.abs(b - a).max() / max_step)))
        out.extend(a + (b - a) * k / n for k in range(1, n + 1))
    return np.array(out)


def _array(state, dof: int) -> np.ndarray:
    return np.array([state[j] for j in range(dof)])
