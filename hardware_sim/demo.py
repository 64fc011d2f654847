"""One recognition of a randomly posed object, printed step by step."""

from __future__ import annotations

import math
from typing import TextIO

import numpy as np

from hardware_sim.world import random_world
from planner.library import load_objects
from planner.plans import PlannedPath
from planner.session import Session
from planner.strategies import StrategyConfig, plan
from planner.types import SensingPath, SensorBounds, Workspace

__all__ = ["run_demo"]


def _next_path(
    session: Session, sensor_position: tuple[float, float], rng: np.random.Generator
) -> tuple[SensingPath, PlannedPath]:
    """The planner's best path (lookahead, depth 2) for the current hypotheses."""
    result = plan(
        session.hypotheses,
        session.models_by_name,
        session.sensor,
        session.workspace,
        sensor_position,
        StrategyConfig(name="lookahead", budget_ms=1000),
        rng=rng,
        observations=session.observations,
    )
    if not result.paths:
        raise RuntimeError(f"the planner has no path to offer ({result.status})")
    best = result.paths[0]
    return best.path, best


def _num(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def run_demo(objects: str, seed: int, max_touches: int, out: TextIO) -> int:
    """Recognize one random object in process; exit code 0 when localized correctly."""
    from app.cli import embedded_set

    path = embedded_set(objects) if not objects.endswith(".json") else objects
    models = load_objects(path)
    workspace = Workspace((0.0, 0.0), 200.0)
    bounds = SensorBounds(1.0, math.radians(3.0))
    rng = np.random.default_rng(seed)
    world = random_world(models, workspace, rng)
    print(
        f"truth: {world.model.name} (stable pose {world.pose_index}) at x={world.pose.x:.1f} "
        f"y={world.pose.y:.1f} theta={math.degrees(world.pose.theta):.1f} deg",
        file=out,
    )
    session = Session(models, bounds, workspace)
    sensor_position = (workspace.radius, 0.0)
    for step in range(1, max_touches + 1):
        path, planned = _next_path(session, sensor_position, rng)
        sensor_position = path.origin
        obs, _ = world.execute(path, bounds, rng)
        session = session.observe(obs)
        what = (
            "miss"
            if obs.contact is None
            else f"contact ({obs.contact.point[0]:.1f}, {obs.contact.point[1]:.1f}) "
            f"normal {math.degrees(obs.contact.normal_angle):.0f} deg"
        )
        classes = len({h.equivalence_class for h in session.hypotheses})
        print(
            f"touch {step}: from ({path.origin[0]:.0f}, {path.origin[1]:.0f}) "
            f"[P(DM) {_num(planned.p_distinguishing)}, "
            f"E[touches] {_num(planned.expected_remaining)}]"
            f" -> {what}; {len(session.hypotheses)} hypotheses in {classes} classes, "
            f"status {session.status}",
            file=out,
        )
        if session.status in ("localized", "inconsistent"):
            break
    if session.status != "localized":
        print(f"not localized after {step} touches ({session.status})", file=out)
        return 1
    best = session.hypotheses[0]
    error = math.hypot(best.pose.x - world.pose.x, best.pose.y - world.pose.y)
    right = best.object == world.model.name and best.stable_pose == world.pose_index
    print(
        f"localized: {best.object} (stable pose {best.stable_pose}) at x={best.pose.x:.1f} "
        f"y={best.pose.y:.1f}, {error:.2f} from the truth "
        f"(bound {best.error_bound.translation:.2f})",
        file=out,
    )
    return 0 if right and error <= best.error_bound.translation + 1e-9 else 1
