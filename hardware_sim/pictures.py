"""Pictures of a recognition in progress, for people to look at."""

from __future__ import annotations

import math

from hardware_sim.world import World
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan
from planner.recognition.session import Session
from planner.render import session_picture as draw_session
from planner.types import (
    Contact,
    ObjectModel,
    Observation,
    Pose,
    SensingPath,
    SensorBounds,
    Workspace,
)

__all__ = ["bump_block_pair", "curved_parts", "session_picture"]


def session_picture(
    session: Session,
    sensor_position: tuple[float, float],
    strategy: str = "lookahead",
    fmt: str = "png",
    grid_size: int = 70,
    paths: int = 3,
) -> bytes:
    """The vector and grid MII of a session with its best planned paths (`strategy`,
    5 s budget, seeded) labelled by P(DM) (:func:`planner.render.session_picture`)."""
    ranked = plan(
        session.hypotheses,
        session.models_by_name,
        session.sensor,
        session.workspace,
        sensor_position,
        StrategyConfig(name=strategy, budget_ms=5000),
        rng=0,
        observations=session.observations,
    )
    n = len(session.hypotheses)
    return draw_session(
        session,
        sensor_position,
        ranked,
        fmt="png" if fmt == "png" else "svg",
        view="both",
        grid_size=grid_size,
        paths=paths,
        title=f"{n} hypotheses after {len(session.observations)} touches ({strategy})",
    )


def bump_block_pair(models: list[ObjectModel]) -> Session:
    """The thesis' Exp. III situation: `bump_block` and its twin touched twice (bottom, left),
    which leaves both objects in both orientations the two touches allow."""
    workspace = Workspace((50.0, 40.0), 160.0)
    session = Session(models, SensorBounds(0.5, math.radians(2.0)), workspace)
    touches = [
        Observation(
            SensingPath((30.0, -120.0), (0.0, 1.0), 320.0), Contact((30.0, 0.0), (0.0, -1.0))
        ),
        Observation(
            SensingPath((-110.0, 30.0), (1.0, 0.0), 320.0), Contact((0.0, 30.0), (-1.0, 0.0))
        ),
    ]
    for obs in touches:
        session = session.observe(obs)
    return session


def curved_parts(models: list[ObjectModel]) -> Session:
    """The curved parts (D shape, stadium, ellipse, cam) with the cam touched exactly
    twice, from below and from the left, at 1 mm / 3 degrees: what is left of four
    finely drawn curves after two contacts."""
    workspace = Workspace((0.0, 0.0), 160.0)
    cam = next(m for m in models if m.name == "cam")
    world = World(cam, 0, Pose(10.0, 5.0, math.radians(20.0)), workspace)
    session = Session(models, SensorBounds(1.0, math.radians(3.0)), workspace)
    for path in (
        SensingPath((5.0, -160.0), (0.0, 1.0), 320.0),
        SensingPath((-160.0, 15.0), (1.0, 0.0), 320.0),
    ):
        session = session.observe(world.execute(path)[0])
    return session
