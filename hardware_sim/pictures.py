"""Pictures of a recognition in progress, for people to look at."""

from __future__ import annotations

import math

from planner.image.grid import build_grid
from planner.image.vector import build_mii
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan
from planner.recognition.session import Session
from planner.render import render_png, render_svg
from planner.types import Contact, ObjectModel, Observation, SensingPath, SensorBounds, Workspace

__all__ = ["bump_block_pair", "session_picture"]


def session_picture(
    session: Session,
    sensor_position: tuple[float, float],
    strategy: str = "lookahead",
    fmt: str = "png",
    grid_size: int = 70,
    paths: int = 3,
) -> bytes:
    """The vector and grid MII of a session with its best planned paths labelled by P(DM)."""
    models = session.models_by_name
    hyps = session.hypotheses
    ranked = plan(
        hyps,
        models,
        session.sensor,
        session.workspace,
        sensor_position,
        StrategyConfig(name=strategy, budget_ms=5000),
        rng=0,
        observations=session.observations,
    ).paths[:paths]
    mii = build_mii(hyps, models)
    grid = build_grid(hyps, models, grid_size)
    render = render_png if fmt == "png" else render_svg
    return render(
        mii,
        grid,
        contacts=list(session.observations),
        workspace=session.workspace,
        sensor_position=sensor_position,
        paths=[p.path for p in ranked],
        p_distinguishing=[p.p_distinguishing for p in ranked],
        title=f"{len(hyps)} hypotheses after {len(session.observations)} touches ({strategy})",
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
