"""Theory = outcome model: what the planner calls certain happens (DESIGN §4.11-4.12)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hardware_sim.world import random_world
from planner.session import Session
from planner.strategies import StrategyConfig, analyse
from planner.types import SensingPath, SensorBounds
from tests.conftest import SET_NAMES, WORKSPACE, object_set

BOUNDS = [SensorBounds(0.0, 0.0), SensorBounds(1.0, math.radians(3))]


@pytest.mark.parametrize("name", SET_NAMES)
@pytest.mark.parametrize("bounds", BOUNDS, ids=["exact", "1mm-3deg"])
@settings(max_examples=12, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), touches=st.integers(2, 3))
def test_a_path_sure_to_distinguish_leaves_one_class(name, bounds, seed, touches):
    # any error within the bounds, on the true object: the session is then localized
    rng = np.random.default_rng(seed)
    models = object_set(name)
    world = random_world(models, WORKSPACE, rng)
    session = Session(models, bounds, WORKSPACE)
    for _ in range(touches):
        session = session.observe(world.execute(world.hitting_path(rng), bounds, rng)[0])
    if session.status != "ambiguous":
        return
    found = analyse(
        session.hypotheses,
        session.models,
        session.sensor,
        session.workspace,
        (WORKSPACE.radius, 0.0),
        StrategyConfig(budget_ms=None),
        0,
        observations=session.observations,
    )
    c = found.candidates
    for i in np.flatnonzero(found.info.p_distinguishing >= 1 - 1e-9)[:4]:
        path = SensingPath(tuple(c.origins[i]), tuple(c.directions[i]), float(c.lengths[i]))
        observation, _ = world.execute(path, bounds, rng, edge_share=0.5)
        assert session.observe(observation).status == "localized"
