"""Shared test catalogue: the object sets, the standard safe circle, seeded worlds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hardware_sim.world import random_world
from planner.library import load_objects
from planner.session import Session
from planner.types import ObjectModel, SensorBounds, Workspace

DATA = Path(__file__).resolve().parents[1] / "planner" / "data"
SET_NAMES = ["thesis_like", "workshop", "symmetric", "mcube_prisms", "table_poses"]
WORKSPACE = Workspace((0.0, 0.0), 200.0)


def object_set(name: str) -> list[ObjectModel]:
    return load_objects(DATA / f"{name}.json")


@pytest.fixture(params=SET_NAMES)
def set_name(request: pytest.FixtureRequest) -> str:
    return request.param


def touched_session(name: str, bounds: SensorBounds, seed: int, touches: int):
    """A world of set `name` drawn from the prior and a session after `touches`
    paths that hit it, errors within `bounds`; returns (world, session, rng)."""
    rng = np.random.default_rng(seed)
    models = object_set(name)
    world = random_world(models, WORKSPACE, rng)
    session = Session(models, bounds, WORKSPACE)
    for _ in range(touches):
        session = session.observe(world.execute(world.hitting_path(rng), bounds, rng)[0])
    return world, session, rng


def analysed(session: Session):
    """The planner's analysis of a session's state (default strategy, no budget),
    planned from (R, 0) on the safe circle."""
    from planner.strategies import StrategyConfig, analyse

    return analyse(
        session.hypotheses,
        session.models,
        session.sensor,
        session.workspace,
        (WORKSPACE.radius, 0.0),
        StrategyConfig(budget_ms=None),
        0,
        observations=session.observations,
    )
